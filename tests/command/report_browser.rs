//! report.html in a real browser: headless Chromium, driven over the DevTools protocol,
//! loads the report of a run, renders it without console errors or exceptions, draws
//! the blocks, and the animation advances when played and follows the slider.
//!
//! Chromium is looked for as `$DDA_CHROMIUM`, then `chromium`, `chromium-browser` and
//! `google-chrome` on the PATH (CI installs Debian's `chromium`). Without one, the test
//! says so and is skipped; this is the only test that may be skipped.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use serde_json::{Value, json};
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/scenes/sliding-block.toml"
);

fn find_chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("DDA_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in ["chromium", "chromium-browser", "google-chrome"] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Headless Chromium, killed when dropped.
struct Browser {
    child: Child,
    ws_url: String,
    _profile: PathBuf,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    fn launch(exe: &Path, profile: PathBuf) -> Browser {
        let _ = std::fs::remove_dir_all(&profile);
        std::fs::create_dir_all(&profile).unwrap();
        let mut child = Command::new(exe)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = child.stderr.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if let Some(at) = line.find("ws://") {
                    let _ = tx.send(line[at..].trim().to_string());
                }
            }
        });
        let ws_url = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("Chromium did not print its DevTools address");
        Browser {
            child,
            ws_url,
            _profile: profile,
        }
    }
}

/// A DevTools connection with one page session; collects the page's errors.
struct Page {
    ws: WebSocket<TcpStream>,
    next_id: u64,
    session: String,
    errors: Vec<String>,
    loaded: bool,
}

impl Page {
    fn open(b: &Browser) -> Page {
        let rest = b.ws_url.strip_prefix("ws://").unwrap();
        let host = rest.split('/').next().unwrap();
        let stream = TcpStream::connect(host).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(30)))
            .unwrap();
        let (ws, _) = tungstenite::client(b.ws_url.as_str(), stream).unwrap();
        let mut p = Page {
            ws,
            next_id: 0,
            session: String::new(),
            errors: Vec::new(),
            loaded: false,
        };
        let target = p.call("Target.createTarget", json!({"url": "about:blank"}));
        let target_id = target["targetId"].as_str().unwrap().to_string();
        let attached = p.call(
            "Target.attachToTarget",
            json!({"targetId": target_id, "flatten": true}),
        );
        p.session = attached["sessionId"].as_str().unwrap().to_string();
        for m in ["Runtime.enable", "Log.enable", "Page.enable"] {
            p.call(m, json!({}));
        }
        p
    }

    /// Reads one message; records errors and the load event.
    fn read(&mut self) -> Value {
        loop {
            match self.ws.read().unwrap() {
                Message::Text(t) => {
                    let v: Value = serde_json::from_str(t.as_str()).unwrap();
                    match v["method"].as_str() {
                        Some("Runtime.exceptionThrown") => self
                            .errors
                            .push(v["params"]["exceptionDetails"].to_string()),
                        Some("Runtime.consoleAPICalled")
                            if matches!(
                                v["params"]["type"].as_str(),
                                Some("error" | "assert" | "warning")
                            ) =>
                        {
                            self.errors.push(v["params"]["args"].to_string())
                        }
                        Some("Log.entryAdded")
                            if v["params"]["entry"]["level"].as_str() == Some("error") =>
                        {
                            self.errors.push(v["params"]["entry"].to_string())
                        }
                        Some("Page.loadEventFired") => self.loaded = true,
                        _ => {}
                    }
                    return v;
                }
                Message::Close(_) => panic!("DevTools closed the connection"),
                _ => {}
            }
        }
    }

    /// Sends a command (in the page session once attached) and waits for its result.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            msg["sessionId"] = json!(self.session);
        }
        self.ws.send(Message::text(msg.to_string())).unwrap();
        loop {
            let v = self.read();
            if v["id"].as_u64() == Some(id) {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    /// Evaluates `js` in the page and returns its value.
    fn eval(&mut self, js: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": js, "returnByValue": true, "awaitPromise": true}),
        );
        assert!(r.get("exceptionDetails").is_none(), "{js}: {r}");
        r["result"]["value"].clone()
    }

    fn navigate(&mut self, url: &str) {
        self.loaded = false;
        self.call("Page.navigate", json!({"url": url}));
        let start = Instant::now();
        while !self.loaded {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "page did not load"
            );
            self.read();
        }
    }
}

/// Counts the canvas pixels that are not white.
const INKED: &str = "(() => { const c = document.getElementById('view'); \
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; let n = 0; \
    for (let i = 0; i < d.length; i += 4) { if (d[i] < 250 || d[i + 1] < 250 || d[i + 2] < 250) n++; } \
    return n; })()";

fn sleep_ms(ms: u64) {
    std::thread::sleep(Duration::from_millis(ms));
}

/// Runs `scene_text` with `dda run` into `dir/out` and returns the report's path.
fn report_of(dir: &Path, scene_text: &str) -> PathBuf {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, scene_text).unwrap();
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_dda"))
        .args(["run", scene.to_str().unwrap(), "--out"])
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    out.join("report.html")
}

#[test]
fn report_renders_and_animates_in_headless_chromium() {
    let Some(exe) = find_chromium() else {
        eprintln!(
            "SKIPPED report_renders_and_animates_in_headless_chromium: no Chromium found \
             (set DDA_CHROMIUM or install Debian's `chromium`)"
        );
        return;
    };
    let dir = std::env::temp_dir().join(format!("dda-browser-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let good = std::fs::read_to_string(SCENE).unwrap();
    // A run that completes, and one that fails (its report shows the diagnosis): a
    // penalty too soft for the motion lets a contact penetrate beyond d_tol.
    let failing = good.replace("normal_penalty = 1e9", "normal_penalty = 2e6");
    let browser = Browser::launch(&exe, dir.join("profile"));
    let mut page = Page::open(&browser);
    for (name, text, failed) in [("completed", &good, false), ("failed", &failing, true)] {
        let case = dir.join(name);
        std::fs::create_dir_all(&case).unwrap();
        let report = report_of(&case, text);
        page.navigate(&format!("file://{}", report.display()));
        // The page unpacks its frames before it draws (asynchronously).
        let started = Instant::now();
        while page.eval("typeof window.ddaReport") != json!("object") {
            assert!(
                started.elapsed() < Duration::from_secs(10),
                "{name}: never drawn"
            );
            sleep_ms(50);
        }

        let frames = page.eval("window.ddaReport.frames").as_u64().unwrap();
        assert!(frames >= 2, "{name}: {frames} frames");
        assert_eq!(page.eval("window.ddaReport.frame()"), json!(0));
        let inked = page.eval(INKED).as_u64().unwrap();
        assert!(
            inked > 1000,
            "{name}: the canvas shows the blocks ({inked} pixels)"
        );
        let label0 = page.eval("document.getElementById('time').textContent");
        assert!(
            label0.as_str().unwrap().starts_with("t = 0.0000 s"),
            "{label0}"
        );
        let shows_failure = page
            .eval("document.body.textContent.includes('Why the run stopped')")
            .as_bool()
            .unwrap();
        assert_eq!(shows_failure, failed, "{name}");

        // Play: the animation advances, and the label follows.
        page.eval("document.getElementById('play').click()");
        sleep_ms(400);
        let k = page.eval("window.ddaReport.frame()").as_u64().unwrap();
        assert!(k > 0, "{name}: the animation did not advance");
        let label = page.eval("document.getElementById('time').textContent");
        assert_ne!(label, label0);
        // Pause stops it (a short animation may have stopped at its end); the slider
        // moves it.
        if page.eval("window.ddaReport.playing()") == json!(true) {
            page.eval("document.getElementById('play').click()");
        }
        assert_eq!(page.eval("window.ddaReport.playing()"), json!(false));
        let paused = page.eval("window.ddaReport.frame()");
        sleep_ms(200);
        assert_eq!(page.eval("window.ddaReport.frame()"), paused);
        let last = frames - 1;
        page.eval(&format!(
            "(() => {{ const s = document.getElementById('slider'); s.value = '{last}'; \
             s.dispatchEvent(new Event('input')); }})()"
        ));
        assert_eq!(page.eval("window.ddaReport.frame()"), json!(last));
        assert!(page.eval(INKED).as_u64().unwrap() > 1000);

        // The view: a scale bar is drawn; the wheel zooms and a drag pans (the view
        // changes); hovering the sliding block names it; Fit all restores the view.
        let scale = page.eval("document.getElementById('scale').textContent");
        assert!(scale.as_str().unwrap().ends_with(" m"), "{scale}");
        let fitted = page.eval("window.ddaReport.view()");
        page.eval(
            "(() => { const c = document.getElementById('view'); const r = c.getBoundingClientRect(); \
             c.dispatchEvent(new WheelEvent('wheel', { deltaY: -300, clientX: r.left + r.width / 2, \
             clientY: r.top + r.height / 2, cancelable: true })); })()",
        );
        let zoomed = page.eval("window.ddaReport.view()");
        assert!(
            zoomed[2].as_f64().unwrap() > 1.5 * fitted[2].as_f64().unwrap(),
            "{fitted} {zoomed}"
        );
        page.eval(
            "(() => { const c = document.getElementById('view'); \
             c.dispatchEvent(new MouseEvent('mousedown', { clientX: 100, clientY: 100 })); \
             c.dispatchEvent(new MouseEvent('mousemove', { clientX: 160, clientY: 130 })); \
             window.dispatchEvent(new MouseEvent('mouseup', {})); })()",
        );
        let panned = page.eval("window.ddaReport.view()");
        assert!(
            panned[0] != zoomed[0] && panned[1] != zoomed[1],
            "{zoomed} {panned}"
        );
        page.eval("document.getElementById('fit').click()");
        assert_eq!(page.eval("window.ddaReport.view()"), fitted);
        // The slider (block 1) at the last frame: hover its centroid.
        let hover = page.eval(
            "(() => { const b = window.ddaReport.blocks(window.ddaReport.frames - 1)[1]; \
             let x = 0, y = 0; \
             for (let j = 0; j < b.length; j += 2) { x += b[j]; y += b[j + 1]; } \
             const n = b.length / 2; const [cx, cy] = window.ddaReport.client(x / n, y / n); \
             document.getElementById('view').dispatchEvent(new MouseEvent('mousemove', { clientX: cx, clientY: cy })); \
             return document.getElementById('hover').textContent; })()",
        );
        assert!(
            hover.as_str().unwrap().starts_with("block slider"),
            "{name}: {hover}"
        );
        // Every tick label of the plots lies inside its picture.
        let outside = page.eval(
            "(() => { let bad = []; for (const svg of document.querySelectorAll('.plots svg')) { \
             const s = svg.getBoundingClientRect(); \
             for (const t of svg.querySelectorAll('text')) { const b = t.getBoundingClientRect(); \
             if (b.left < s.left - 0.5 || b.top < s.top - 0.5 || b.right > s.right + 0.5 \
             || b.bottom > s.bottom + 0.5) bad.push(t.textContent); } } \
             return bad; })()",
        );
        assert_eq!(outside, json!([]), "{name}: labels outside their plot");

        // Colour by stress (the blocks are elastic): the legend says so, the canvas
        // is drawn anew.
        page.eval(
            "(() => { const s = document.getElementById('colour'); s.value = 's3'; \
             s.dispatchEvent(new Event('change')); })()",
        );
        let legend = page.eval("document.getElementById('legend').textContent");
        assert!(
            legend
                .as_str()
                .unwrap()
                .starts_with("minor principal stress"),
            "{legend}"
        );
        assert!(page.eval(INKED).as_u64().unwrap() > 1000);

        // The page's frames are frames.jsonl's, at the page's resolution (1e-4 of the
        // view, here 1 mm: every coordinate within half of it).
        let lines = std::fs::read_to_string(report.with_file_name("frames.jsonl")).unwrap();
        let jsonl: Vec<Value> = lines
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(jsonl.len() as u64, frames);
        for k in [0, frames as usize / 2, frames as usize - 1] {
            let page_blocks = page.eval(&format!("window.ddaReport.blocks({k})"));
            for (a, b) in page_blocks
                .as_array()
                .unwrap()
                .iter()
                .zip(jsonl[k]["blocks"].as_array().unwrap())
            {
                for (x, y) in a.as_array().unwrap().iter().zip(b.as_array().unwrap()) {
                    let d = (x.as_f64().unwrap() - y.as_f64().unwrap()).abs();
                    assert!(d <= 0.5e-3 + 1e-12, "{name}: frame {k}: {x} against {y}");
                }
            }
        }

        // Let any late error arrive.
        sleep_ms(100);
        page.eval("1");
        assert!(page.errors.is_empty(), "{name}: {:?}", page.errors);
    }
}

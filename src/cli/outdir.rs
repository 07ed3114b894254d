//! The output folder rules: a run never deletes or overwrites a file it did not write.
//!
//! - A run writes into a staging folder beside its output folder (`.NAME.partial`),
//!   created by the run itself, and moves it into place when it ends.
//! - Every folder a run writes carries a marker file ([`MARKER`]). An existing `--out`
//!   is replaced only if it is a finished run of ours: it has the marker and holds only
//!   the files a run writes ([`is_own`]). Anything else (a folder without the marker, a
//!   file of the user's inside it, the working directory or one of its ancestors, a
//!   path that is not a folder) is refused before anything is written.
//! - One process per run folder: while `run` or `resume` works, it holds an advisory
//!   lock on a file in the staging folder ([`LOCK`], holding its process id). The
//!   operating system releases the lock when the process ends, however it ends, so a
//!   lock is never stale; a second `run` or `resume` is refused at once, naming the
//!   process.

use super::Failure;
use std::fs::File;
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The marker file of a folder written by `dda run`.
pub const MARKER: &str = ".dda-run";
/// The lock file in a staging folder.
pub const LOCK: &str = ".dda-lock";
/// The files a run writes at the top of its folder (besides [`MARKER`], [`LOCK`] and
/// the `frames` folder).
const OWN_FILES: [&str; 8] = [
    "summary.json",
    "history.csv",
    "measurements.csv",
    "bolts.csv",
    "frames.jsonl",
    "report.html",
    "scene.json",
    "checkpoint.bin",
];

/// Whether `name` is a file a run writes at the top of its folder: an output, the
/// marker or lock, or the temporary sibling (`.NAME.tmp`) an atomic write leaves for an
/// instant.
pub fn is_own(name: &str) -> bool {
    let base = name
        .strip_prefix('.')
        .and_then(|n| n.strip_suffix(".tmp"))
        .unwrap_or(name);
    name == MARKER || name == LOCK || OWN_FILES.contains(&base)
}

/// Whether `name` is a picture a run draws in its `frames` folder (`frame-NNNN.svg`).
fn is_own_frame(name: &str) -> bool {
    name.strip_prefix("frame-")
        .and_then(|n| n.strip_suffix(".svg"))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

fn bad(msg: String) -> Failure {
    Failure::Input(msg)
}

/// An output failure naming `path` and the system's error.
pub fn output_error(e: std::io::Error, path: &Path) -> Failure {
    Failure::Output(format!("cannot write {}: {e}", path.display()))
}

/// The names in folder `dir` that a run did not write, if any (with `frames/`'s).
fn foreign_entries(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut foreign = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let kind = entry.file_type()?;
        if name == "frames" && kind.is_dir() {
            for f in std::fs::read_dir(entry.path())? {
                let f = f?;
                let fname = f.file_name().to_string_lossy().into_owned();
                if !(f.file_type()?.is_file() && is_own_frame(&fname)) {
                    foreign.push(format!("frames/{fname}"));
                }
            }
        } else if !(kind.is_file() && is_own(&name)) {
            foreign.push(name);
        }
    }
    foreign.sort();
    Ok(foreign)
}

/// Refuses `dir` unless it is a folder written by a run (the marker) holding only what
/// a run writes; `what` names its role in the message.
fn check_own_folder(dir: &Path, what: &str) -> Result<(), Failure> {
    let refuse = |why: String| {
        bad(format!(
            "{what} {} {why}; dda writes only into a new folder or one an earlier \
             `dda run` wrote, and never deletes a file it did not write: choose another \
             --out",
            dir.display()
        ))
    };
    if !dir.is_dir() {
        return Err(refuse("exists and is not a folder".into()));
    }
    if !dir.join(MARKER).is_file() {
        return Err(refuse(format!(
            "exists and is not a dda run folder (it has no {MARKER} marker)"
        )));
    }
    let foreign = foreign_entries(dir).map_err(|e| refuse(format!("cannot be read ({e})")))?;
    if !foreign.is_empty() {
        let mut list = foreign
            .iter()
            .take(5)
            .cloned()
            .collect::<Vec<_>>()
            .join(", ");
        if foreign.len() > 5 {
            list.push_str(&format!(" and {} more", foreign.len() - 5));
        }
        return Err(refuse(format!("holds files dda did not write: {list}")));
    }
    Ok(())
}

/// Refuses `path` if it is a symbolic link: a run replaces its output folder (and moves
/// its staging folder) whole, and would replace the link, which it did not write, after
/// removing the files of the run it points to; `what` names its role in the message.
fn not_a_link(path: &Path, what: &str) -> Result<(), Failure> {
    if path
        .symlink_metadata()
        .is_ok_and(|m| m.file_type().is_symlink())
    {
        return Err(bad(format!(
            "{what} {} is a symbolic link; a run replaces its folder whole, and dda never \
             replaces a file it did not write: give the folder itself, or a new one",
            path.display()
        )));
    }
    Ok(())
}

/// Checks that `out` may receive a run's results: a new path, or a finished run of
/// ours that may be replaced (not through a symbolic link); never the working
/// directory or one of its ancestors.
pub fn check_out(out: &Path) -> Result<(), Failure> {
    if out.file_name().is_none() {
        return Err(bad(format!(
            "--out {}: name a folder for the results (not `.`, `..` or `/`)",
            out.display()
        )));
    }
    if let (Ok(dir), Ok(cwd)) = (out.canonicalize(), std::env::current_dir())
        && cwd.canonicalize().unwrap_or(cwd).starts_with(&dir)
    {
        return Err(bad(format!(
            "--out {} is the working directory or one of its ancestors; dda never writes \
             its results over the folder it runs in: choose a new folder",
            out.display()
        )));
    }
    if out.symlink_metadata().is_ok() {
        not_a_link(out, "--out")?;
        check_own_folder(out, "--out")?;
    }
    Ok(())
}

/// The staging folder of `out`: a sibling, `.NAME.partial`.
pub fn staging_dir(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    out.with_file_name(format!(".{name}.partial"))
}

/// The staging folder and the output folder named by `dir`, which may be either.
pub fn work_and_out(dir: &Path) -> (PathBuf, PathBuf) {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match name
        .strip_prefix('.')
        .and_then(|n| n.strip_suffix(".partial"))
    {
        Some(base) => (dir.to_path_buf(), dir.with_file_name(base)),
        None => (staging_dir(dir), dir.to_path_buf()),
    }
}

/// A staging folder held by this process: its lock, and whether this process created
/// it (then an output failure removes it whole).
pub struct Staging {
    /// The folder.
    pub dir: PathBuf,
    /// Whether this process created it.
    fresh: bool,
    /// Whether it now holds a finished run that could not be moved into place, to keep.
    keep: bool,
    _lock: File,
}

impl Staging {
    /// Creates the staging folder `work` of a new run, or clears a leftover one of ours
    /// that holds no checkpoint. Refuses a folder in use, one holding an interrupted
    /// run (which `dda resume` continues), and anything not written by dda.
    pub fn create(work: &Path, out: &Path) -> Result<Staging, Failure> {
        if work.symlink_metadata().is_ok() {
            not_a_link(work, "the staging folder")?;
            check_own_folder(work, "the staging folder")?;
            let lock = lock(work)?;
            if work.join(super::run::CHECKPOINT_FILE).exists() {
                return Err(bad(format!(
                    "{} holds an interrupted run of this output: `dda resume {}` continues \
                     it; to start afresh, delete {} first",
                    work.display(),
                    out.display(),
                    work.display()
                )));
            }
            // A leftover of ours (checked above): only our own files are removed.
            remove_own(work).map_err(|e| output_error(e, work))?;
            drop(lock);
        }
        if let Some(parent) = work.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|e| output_error(e, parent))?;
        }
        match std::fs::create_dir(work) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                return Err(bad(format!(
                    "{} was just created by another dda process starting a run into {}",
                    work.display(),
                    out.display()
                )));
            }
            Err(e) => return Err(output_error(e, work)),
        }
        let made = (|| {
            std::fs::write(work.join(MARKER), marker_text()).map_err(|e| output_error(e, work))?;
            lock(work)
        })();
        match made {
            Ok(lock) => Ok(Staging {
                dir: work.to_path_buf(),
                fresh: true,
                keep: false,
                _lock: lock,
            }),
            Err(e) => {
                let _ = remove_own(work);
                Err(e)
            }
        }
    }

    /// Takes over the staging folder `work` of an interrupted run, to resume it.
    pub fn resume(work: &Path) -> Result<Staging, Failure> {
        not_a_link(work, "the staging folder")?;
        check_own_folder(work, "the staging folder")?;
        Ok(Staging {
            dir: work.to_path_buf(),
            fresh: false,
            keep: false,
            _lock: lock(work)?,
        })
    }

    /// After an output failure: removes the folder if this process created it (all of
    /// it is ours), else only the temporary files of atomic writes, keeping the
    /// interrupted run's checkpoint.
    pub fn abandon(self) {
        if self.fresh && !self.keep {
            let _ = remove_own(&self.dir);
        } else if let Ok(entries) = std::fs::read_dir(&self.dir) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if name.starts_with('.') && name.ends_with(".tmp") && is_own(&name) {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
    }

    /// Moves the finished run into `out`, replacing an earlier run of ours there (its
    /// own files only; checked again now, as the user may have added files since the
    /// run began). If that fails, the staging folder is kept: it holds the whole run.
    pub fn publish(&mut self, out: &Path) -> Result<(), Failure> {
        self.keep = true;
        if out.symlink_metadata().is_ok() {
            not_a_link(out, "--out")
                .and_then(|()| check_own_folder(out, "--out"))
                .map_err(|e| match e {
                    Failure::Input(m) | Failure::Output(m) => Failure::Output(format!(
                        "{m} (it changed during the run; the results are kept in {})",
                        self.dir.display()
                    )),
                })?;
            remove_own(out).map_err(|e| output_error(e, out))?;
        }
        std::fs::rename(&self.dir, out).map_err(|e| output_error(e, out))?;
        let _ = std::fs::remove_file(out.join(LOCK));
        Ok(())
    }
}

/// The marker's text: which program wrote the folder.
fn marker_text() -> String {
    format!(
        "This folder was written by dda {} (dda run); `dda run --out` may replace it.\n",
        env!("CARGO_PKG_VERSION")
    )
}

/// Removes folder `dir` of ours: its own files, `frames/`'s pictures, then the folders
/// (which fails, keeping them, if anything else is there).
fn remove_own(dir: &Path) -> std::io::Result<()> {
    let frames = dir.join("frames");
    if frames.is_dir() {
        for f in std::fs::read_dir(&frames)? {
            let f = f?;
            if is_own_frame(&f.file_name().to_string_lossy()) {
                std::fs::remove_file(f.path())?;
            }
        }
        std::fs::remove_dir(&frames)?;
    }
    for e in std::fs::read_dir(dir)? {
        let e = e?;
        if e.file_type()?.is_file() && is_own(&e.file_name().to_string_lossy()) {
            std::fs::remove_file(e.path())?;
        }
    }
    std::fs::remove_dir(dir)
}

/// Locks `work`'s lock file for this process, writing its id there; refuses (exit 2)
/// when another process holds it.
fn lock(work: &Path) -> Result<File, Failure> {
    let path = work.join(LOCK);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|e| output_error(e, &path))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut pid = String::new();
            let _ = file.read_to_string(&mut pid);
            let pid = pid.trim();
            return Err(bad(format!(
                "{} is in use by another dda process{} (a run or resume into it); wait \
                 for it to end, or stop it",
                work.display(),
                if pid.is_empty() {
                    String::new()
                } else {
                    format!(", process {pid}")
                }
            )));
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(output_error(e, &path)),
    }
    let written = file
        .set_len(0)
        .and_then(|_| file.rewind())
        .and_then(|_| writeln!(file, "{}", std::process::id()))
        .and_then(|_| file.flush());
    written.map_err(|e| output_error(e, &path))?;
    Ok(file)
}

/// Whether `dir` is a folder written by a run (for `dda render`).
pub fn check_run_folder(dir: &Path) -> Result<(), Failure> {
    check_own_folder(dir, "the run folder")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn own_names_are_the_outputs_and_their_temporaries() {
        for n in [
            "summary.json",
            ".summary.json.tmp",
            MARKER,
            LOCK,
            "checkpoint.bin",
        ] {
            assert!(is_own(n), "{n}");
        }
        for n in [
            "notes.txt",
            ".notes.tmp",
            "summary.json.bak",
            "frames",
            ".tmp",
        ] {
            assert!(!is_own(n), "{n}");
        }
        assert!(is_own_frame("frame-0012.svg"));
        for n in ["frame-.svg", "frame-12.png", "my.svg", "frame-1a.svg"] {
            assert!(!is_own_frame(n), "{n}");
        }
    }
}

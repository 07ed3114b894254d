//! The animation's frames packed for report.html: the same numbers as frames.jsonl's
//! lines, as little-endian binary, deflated (zlib) and base64-encoded, so that the
//! page holds them in about a fifth of the text. The page's script inflates them with
//! the browser's own `DecompressionStream`.
//!
//! Layout, after inflating:
//!
//! ```text
//! u32 frames, u32 blocks, f64 per_metre (coordinates are whole numbers of 1/per_metre m)
//! per frame: f64 t, u8 svg, u8 has_stress,
//!   per block: u16 vertices, then 2 i32 per vertex: the coordinate in 1/per_metre m,
//!     less the same coordinate of the frame before when the block had as many
//!     vertices there (small numbers, which deflate well),
//!   f32 speed per block, [3 f32 stress per block when has_stress],
//!   u32 contact points, 2 i32 each (not differenced)
//! ```

use super::Frame;

/// The deflate level of the packed frames. Measured (2026-11-26, whole runs,
/// alternating, five each): the paper's 93-block column, `dda run`'s own job, 0.24 s at
/// level 3 against 0.27 s at level 6 (the report's deflate was 17% of the process), its
/// report.html 652 kB against 621 kB; the 106-block wall's 405 kB against 351 kB, the
/// 826-block column's 1.19 MB against 1.17 MB. Level 1 took 0.23 s for 740 kB. Our
/// choice: a report some 5% to 15% larger for a tenth off a small run.
const DEFLATE_LEVEL: u8 = 3;

/// Packs `frames` (coordinates rounded to 1/`per_metre` m, as [`Frame::of`] makes them),
/// or None if a coordinate does not fit an i32 count (the page then takes the frames
/// as JSON).
pub fn pack_frames(frames: &[Frame], per_metre: f64) -> Option<String> {
    let blocks = frames.first().map_or(0, |f| f.blocks.len());
    let mut out = Vec::new();
    out.extend_from_slice(&(frames.len() as u32).to_le_bytes());
    out.extend_from_slice(&(blocks as u32).to_le_bytes());
    out.extend_from_slice(&per_metre.to_le_bytes());
    let count = |x: f64| -> Option<i32> {
        let c = (x * per_metre).round();
        (c.abs() < f64::from(i32::MAX)).then_some(c as i32)
    };
    let mut last: Vec<Vec<i32>> = vec![Vec::new(); blocks];
    for f in frames {
        if f.blocks.len() != blocks || f.speed.len() != blocks {
            return None;
        }
        out.extend_from_slice(&f.t.to_le_bytes());
        out.push(u8::from(f.svg));
        let stress = f.stress.len() == 3 * blocks;
        out.push(u8::from(stress));
        for (b, prev) in f.blocks.iter().zip(last.iter_mut()) {
            let n = u16::try_from(b.len() / 2).ok()?;
            out.extend_from_slice(&n.to_le_bytes());
            let now: Vec<i32> = b.iter().map(|&x| count(x)).collect::<Option<_>>()?;
            let same = prev.len() == now.len();
            for (k, &c) in now.iter().enumerate() {
                let d = if same { c.wrapping_sub(prev[k]) } else { c };
                out.extend_from_slice(&d.to_le_bytes());
            }
            *prev = now;
        }
        for &v in &f.speed {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
        if stress {
            for &v in &f.stress {
                out.extend_from_slice(&(v as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&((f.contacts.len() / 2) as u32).to_le_bytes());
        for &x in &f.contacts {
            out.extend_from_slice(&count(x)?.to_le_bytes());
        }
    }
    let deflated = miniz_oxide::deflate::compress_to_vec_zlib(&out, DEFLATE_LEVEL);
    Some(base64(&deflated))
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::base64;

    /// RFC 4648's test vectors.
    #[test]
    fn base64_matches_the_standard() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }
}

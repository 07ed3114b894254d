//! Where a key path sits in a scene file: an index from key paths (`blocks[3].vertices`)
//! to 1-based line numbers, built from the TOML parser's spans or by a small JSON scanner,
//! so that errors found after parsing (validation) still name their line.

use std::collections::BTreeMap;

/// Key path -> line of the key (for table entries) or of the value (for array elements).
#[derive(Clone, Debug, Default)]
pub struct LineIndex {
    lines: BTreeMap<String, usize>,
}

impl LineIndex {
    /// Indexes a TOML document; an empty index if it does not parse.
    pub fn toml(text: &str) -> Self {
        let mut index = LineIndex::default();
        if let Ok(root) = toml::de::DeTable::parse(text) {
            let starts = line_starts(text);
            index.walk_toml_table(root.get_ref(), "", &starts);
        }
        index
    }

    /// Indexes a JSON document; as much as was scanned if it is malformed.
    pub fn json(text: &str) -> Self {
        let mut index = LineIndex::default();
        let starts = line_starts(text);
        let mut scan = JsonScan {
            bytes: text.as_bytes(),
            pos: 0,
        };
        scan.document(&starts, &mut index);
        index
    }

    /// The line of `path`, or of its nearest indexed ancestor.
    pub fn line(&self, path: &str) -> Option<usize> {
        let mut p = path;
        loop {
            if let Some(&l) = self.lines.get(p) {
                return Some(l);
            }
            let cut = p.rfind(['.', '['])?;
            p = &p[..cut];
        }
    }

    fn insert(&mut self, path: String, line: usize) {
        self.lines.entry(path).or_insert(line);
    }

    fn walk_toml_table(&mut self, table: &toml::de::DeTable<'_>, prefix: &str, starts: &[usize]) {
        for (key, value) in table.iter() {
            let path = join_key(prefix, key.get_ref());
            self.insert(path.clone(), line_of(starts, key.span().start));
            self.walk_toml_value(value, &path, starts);
        }
    }

    fn walk_toml_value(
        &mut self,
        value: &toml::Spanned<toml::de::DeValue<'_>>,
        path: &str,
        starts: &[usize],
    ) {
        match value.get_ref() {
            toml::de::DeValue::Table(t) => self.walk_toml_table(t, path, starts),
            toml::de::DeValue::Array(a) => {
                for (i, v) in a.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    self.insert(p.clone(), line_of(starts, v.span().start));
                    self.walk_toml_value(v, &p, starts);
                }
            }
            _ => {}
        }
    }
}

/// `prefix.key`, or `key` at the root.
pub(crate) fn join_key(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// Byte offsets at which each line starts.
fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect()
}

/// 1-based line of byte `offset`.
pub(crate) fn line_of(starts: &[usize], offset: usize) -> usize {
    starts.partition_point(|&s| s <= offset).max(1)
}

/// 1-based line of byte `offset` in `text`.
pub(crate) fn line_at(text: &str, offset: usize) -> usize {
    line_of(&line_starts(text), offset)
}

/// How deep arrays and tables nest in a scene text, scanned once in linear time
/// outside strings and comments (TOML's basic, literal and multi-line strings and `#`
/// comments; JSON's strings), or the 1-based line where the nesting first passes
/// `limit`. Run before either parser, so that no parser, nor the line index, meets a
/// document deeper than that.
pub(crate) fn nesting_beyond(text: &str, toml: bool, limit: usize) -> Option<usize> {
    let b = text.as_bytes();
    let (mut i, mut depth, mut line) = (0usize, 0usize, 1usize);
    while i < b.len() {
        match b[i] {
            b'\n' => line += 1,
            b'[' | b'{' => {
                depth += 1;
                if depth > limit {
                    return Some(line);
                }
            }
            b']' | b'}' => depth = depth.saturating_sub(1),
            b'#' if toml => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            q @ (b'"' | b'\'') if toml || q == b'"' => {
                let triple = toml && b[i..].starts_with(&[q, q, q]);
                let escapes = q == b'"';
                i += if triple { 3 } else { 1 };
                // Every pass of this loop moves on at least one byte.
                while i < b.len() {
                    if escapes && b[i] == b'\\' {
                        i += 2;
                        continue;
                    }
                    if b[i] == b'\n' {
                        line += 1;
                        if !triple {
                            break;
                        }
                    }
                    if b[i] == q && (!triple || b[i..].starts_with(&[q, q, q])) {
                        i += if triple { 3 } else { 1 };
                        break;
                    }
                    i += 1;
                }
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// What a [`JsonScan`] is inside: an object, or an array with its next element's index.
enum Open {
    Object(String),
    Array(String, usize),
}

/// A forgiving JSON scanner that records where each key and array element starts; it
/// stops quietly at malformed input (the parser reports that error itself). Iterative,
/// with its own stack no deeper than [`crate::limits::MAX_NESTING`], and every pass of
/// its loop consumes at least one byte, so it ends in time linear in the text whatever
/// the text is.
struct JsonScan<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl JsonScan<'_> {
    fn skip_ws(&mut self) {
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
    }

    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.pos).copied()
    }

    /// Scans a string starting at its opening quote; returns its raw contents.
    fn string(&mut self) -> Option<String> {
        self.pos += 1;
        let start = self.pos;
        while let Some(b) = self.peek() {
            match b {
                b'"' => {
                    let s = String::from_utf8_lossy(&self.bytes[start..self.pos]).into_owned();
                    self.pos += 1;
                    return Some(s);
                }
                b'\\' => self.pos += 2,
                _ => self.pos += 1,
            }
        }
        None
    }

    /// Scans a scalar (number, literal or string) at `pos`, consuming at least a byte.
    fn scalar(&mut self) -> Option<()> {
        if self.peek()? == b'"' {
            return self.string().map(|_| ());
        }
        let start = self.pos;
        while self.peek().is_some_and(|b| {
            !matches!(b, b',' | b'}' | b']' | b'{' | b'[' | b':' | b'"') && !b.is_ascii_whitespace()
        }) {
            self.pos += 1;
        }
        (self.pos > start).then_some(())
    }

    /// Scans the document, recording key and element lines into `index`.
    fn document(&mut self, starts: &[usize], index: &mut LineIndex) -> Option<()> {
        let mut stack: Vec<Open> = Vec::new();
        // The path of the value about to be read, when one is expected.
        let mut pending: Option<String> = Some(String::new());
        loop {
            self.skip_ws();
            if let Some(path) = pending.take() {
                match self.peek()? {
                    // Paths grow with the depth: beyond the nesting a scene may have
                    // (refused before parsing), the scan stops rather than build them.
                    b'{' | b'[' if stack.len() >= crate::limits::MAX_NESTING => return None,
                    b'{' => {
                        self.pos += 1;
                        stack.push(Open::Object(path));
                    }
                    b'[' => {
                        self.pos += 1;
                        stack.push(Open::Array(path, 0));
                    }
                    _ => self.scalar()?,
                }
                continue;
            }
            let top = stack.last_mut()?;
            let byte = self.peek()?;
            match (top, byte) {
                (Open::Object(_), b'}') | (Open::Array(..), b']') => {
                    self.pos += 1;
                    stack.pop();
                    if stack.is_empty() {
                        return Some(());
                    }
                }
                (_, b',') => self.pos += 1,
                (Open::Object(path), b'"') => {
                    let line = line_of(starts, self.pos);
                    let key = self.string()?;
                    let p = join_key(path, &key);
                    index.insert(p.clone(), line);
                    self.skip_ws();
                    if self.peek()? != b':' {
                        return None;
                    }
                    self.pos += 1;
                    pending = Some(p);
                }
                (Open::Array(path, i), _) => {
                    let p = format!("{path}[{i}]");
                    *i += 1;
                    index.insert(p.clone(), line_of(starts, self.pos));
                    pending = Some(p);
                }
                _ => return None,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_paths_have_their_lines() {
        let text = "name = \"x\"\n[analysis]\nduration = 1.0\n\n[[blocks]]\nid = \"a\"\n\
                    vertices = [\n [0.0, 0.0],\n [1.0, 0.0],\n]\n[[blocks]]\nid = \"b\"\n";
        let ix = LineIndex::toml(text);
        assert_eq!(ix.line("name"), Some(1));
        assert_eq!(ix.line("analysis.duration"), Some(3));
        assert_eq!(ix.line("blocks[0].id"), Some(6));
        assert_eq!(ix.line("blocks[0].vertices[1]"), Some(9));
        assert_eq!(ix.line("blocks[1].id"), Some(12));
        // A missing key falls back to its parent.
        assert_eq!(ix.line("blocks[1].material"), Some(11));
    }

    #[test]
    fn json_paths_have_their_lines() {
        let text = "{\n \"name\": \"x\",\n \"analysis\": {\"duration\": 1},\n \"blocks\": [\n  \
                    {\"id\": \"a\\\"q\",\n   \"vertices\": [[0, 0],\n    [1, 0]]}\n ]\n}\n";
        let ix = LineIndex::json(text);
        assert_eq!(ix.line("name"), Some(2));
        assert_eq!(ix.line("analysis.duration"), Some(3));
        assert_eq!(ix.line("blocks[0].id"), Some(5));
        assert_eq!(ix.line("blocks[0].vertices[1]"), Some(7));
        assert_eq!(ix.line("nothing"), None);
    }

    /// Malformed JSON ends the scan: each of these once made it loop or recurse without
    /// end. An element of an array that cannot start a value (`}` in `[}`) is consumed
    /// by no branch, so the scan must stop there.
    #[test]
    fn malformed_json_ends_the_scan() {
        for text in [
            "[}",
            "{\"a\":[}",
            "{\"a\" 1}",
            "[1 2 }",
            "{\"a\":",
            "]]]",
            "{:}",
        ] {
            let _ = LineIndex::json(text);
        }
        let deep = "[".repeat(100_000);
        let _ = LineIndex::json(&deep);
    }

    /// The nesting scan counts brackets outside strings and comments only.
    #[test]
    fn nesting_is_counted_outside_strings_and_comments() {
        assert_eq!(nesting_beyond("a = [[1]]", true, 2), None);
        assert_eq!(nesting_beyond("a = [[[1]]]", true, 2), Some(1));
        assert_eq!(nesting_beyond("a = \"[[[\" # [[[\nb = 1", true, 1), None);
        assert_eq!(
            nesting_beyond("a = \'\'\'\n[[[\'\'\'\nb = [[[1]]]", true, 2),
            Some(3)
        );
        assert_eq!(
            nesting_beyond("{\"a\": \"[[\\\"[\", \"b\": [[1]]}", false, 2),
            Some(1)
        );
        assert_eq!(
            nesting_beyond("{\"a\": \"[[\\\"[\", \"b\": [[1]]}", false, 3),
            None
        );
    }
}

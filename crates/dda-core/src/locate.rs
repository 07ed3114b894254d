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
        scan.value("", &starts, &mut index);
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

/// A forgiving JSON scanner that records where each key and array element starts; it
/// stops quietly at malformed input (the parser reports that error itself).
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

    fn value(&mut self, path: &str, starts: &[usize], index: &mut LineIndex) -> Option<()> {
        self.skip_ws();
        match self.peek()? {
            b'{' => {
                self.pos += 1;
                loop {
                    self.skip_ws();
                    match self.peek()? {
                        b'}' => {
                            self.pos += 1;
                            return Some(());
                        }
                        b',' => self.pos += 1,
                        b'"' => {
                            let line = line_of(starts, self.pos);
                            let key = self.string()?;
                            let p = join_key(path, &key);
                            index.insert(p.clone(), line);
                            self.skip_ws();
                            if self.peek()? != b':' {
                                return None;
                            }
                            self.pos += 1;
                            self.value(&p, starts, index)?;
                        }
                        _ => return None,
                    }
                }
            }
            b'[' => {
                self.pos += 1;
                let mut i = 0;
                loop {
                    self.skip_ws();
                    match self.peek()? {
                        b']' => {
                            self.pos += 1;
                            return Some(());
                        }
                        b',' => self.pos += 1,
                        _ => {
                            let p = format!("{path}[{i}]");
                            index.insert(p.clone(), line_of(starts, self.pos));
                            self.value(&p, starts, index)?;
                            i += 1;
                        }
                    }
                }
            }
            b'"' => self.string().map(|_| ()),
            _ => {
                while self
                    .peek()
                    .is_some_and(|b| !matches!(b, b',' | b'}' | b']') && !b.is_ascii_whitespace())
                {
                    self.pos += 1;
                }
                Some(())
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
}

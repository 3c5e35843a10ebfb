//! Positions as editors count them: a line and a column in UTF-16 code units (the Language
//! Server Protocol's unit), to and from the byte offsets of the spans.

/// A line and a UTF-16 column, both from 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Position {
    pub line: u32,
    pub character: u32,
}

/// Where each line of a text starts. A line ends at `\n`, `\r\n` or a lone `\r`, as editors
/// count them.
#[derive(Debug, Clone)]
pub struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    pub fn new(text: &str) -> Self {
        let bytes = text.as_bytes();
        let mut starts = vec![0];
        let mut i = 0;
        while i < bytes.len() {
            match bytes[i] {
                b'\n' => starts.push(i + 1),
                b'\r' if bytes.get(i + 1) != Some(&b'\n') => starts.push(i + 1),
                _ => {}
            }
            i += 1;
        }
        Self { starts }
    }

    /// The position of byte `offset` of `text` (the text the index was made from); an offset
    /// inside a character or past the end counts as the character's start or the end.
    pub fn position(&self, text: &str, offset: usize) -> Position {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= offset) - 1;
        let start = self.starts[line];
        let character: usize = text[start..offset].chars().map(char::len_utf16).sum();
        Position {
            line: line as u32,
            character: character as u32,
        }
    }

    /// The byte offset of `pos` in `text`: a column past the line's end is its end (before the
    /// line break), a line past the last is the end of the text, and a column inside a
    /// character (between the halves of a surrogate pair) is the character's start.
    pub fn offset(&self, text: &str, pos: Position) -> usize {
        let Some(&start) = self.starts.get(pos.line as usize) else {
            return text.len();
        };
        let end = self
            .starts
            .get(pos.line as usize + 1)
            .copied()
            .unwrap_or(text.len());
        let line = text[start..end].trim_end_matches(['\n', '\r']);
        let mut units = 0usize;
        for (i, c) in line.char_indices() {
            if units + c.len_utf16() > pos.character as usize {
                return start + i;
            }
            units += c.len_utf16();
        }
        start + line.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_count_utf16_units() {
        // `é` is 2 bytes and 1 unit; `😀` is 4 bytes and 2 units.
        let text = "ab\n#declare é😀x = 1;\r\nlast";
        let ix = LineIndex::new(text);
        let x = text.find('x').unwrap();
        let p = ix.position(text, x);
        assert_eq!(
            p,
            Position {
                line: 1,
                character: 12
            }
        );
        assert_eq!(ix.offset(text, p), x);
        // Inside the surrogate pair: the emoji's start.
        let emoji = text.find('😀').unwrap();
        assert_eq!(
            ix.offset(
                text,
                Position {
                    line: 1,
                    character: 11
                }
            ),
            emoji
        );
        // Past the line's end: before its `\r\n`.
        assert_eq!(
            ix.offset(
                text,
                Position {
                    line: 1,
                    character: 99
                }
            ),
            text.find('\r').unwrap()
        );
        assert_eq!(
            ix.position(text, text.len()),
            Position {
                line: 2,
                character: 4
            }
        );
        assert_eq!(
            ix.offset(
                text,
                Position {
                    line: 9,
                    character: 0
                }
            ),
            text.len()
        );
    }

    #[test]
    fn a_lone_carriage_return_ends_a_line() {
        let text = "a\rb\r\nc";
        let ix = LineIndex::new(text);
        assert_eq!(
            ix.position(text, 2),
            Position {
                line: 1,
                character: 0
            }
        );
        assert_eq!(
            ix.position(text, 5),
            Position {
                line: 2,
                character: 0
            }
        );
        // An offset inside a character is its start.
        let t = "é";
        assert_eq!(LineIndex::new(t).position(t, 1), Position::default());
    }
}

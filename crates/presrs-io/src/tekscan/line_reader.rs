//! The lines of a TekScan text, read one at a time from any reader (a file's text, stdin, a pipe).
//!
//! Lines break at `\n`, `\r\n` or a lone `\r`, mixed freely, and are numbered from 1, as
//! [`crate::textutil::numbered_lines`] numbers a whole file; a final line break does not start a line.
//! A `\n` right after a `\r` is taken as part of that break when it is read, never waited for, so that
//! a live stream's line is handed over as soon as its `\r` arrives. A line can be capped in length:
//! the rest of a longer line is then read and dropped, so that a line without end cannot eat memory.

use std::io::BufRead;

/// What [`LineReader::next`] read.
pub(super) enum Line {
    /// The end of the input.
    End,
    /// A line of text: [`LineReader::text`].
    Text,
    /// A line that cannot be read as text (too long, not UTF-8): why. It counts as a line.
    Bad(String),
}

/// Reads numbered lines from `R` (see the module docs).
#[derive(Debug)]
pub(super) struct LineReader<R> {
    reader: R,
    line_no: usize,
    line: Vec<u8>,
    /// The last line ended with `\r`: a `\n` read next belongs to that break.
    after_cr: bool,
    /// The rest of an over-long line is still to be read and dropped.
    discard_line: bool,
    /// The line in `line` is to be read again.
    replay: bool,
}

impl<R: BufRead> LineReader<R> {
    pub(super) fn new(reader: R) -> Self {
        Self {
            reader,
            line_no: 0,
            line: Vec::new(),
            after_cr: false,
            discard_line: false,
            replay: false,
        }
    }

    /// The number of the last line read (0 before the first).
    pub(super) fn line_no(&self) -> usize {
        self.line_no
    }

    /// The last line read, without its break (empty when it was not text).
    pub(super) fn text(&self) -> &str {
        std::str::from_utf8(&self.line).unwrap_or("")
    }

    /// Makes the last line (a [`Line::Text`]) the next one read again.
    pub(super) fn unread(&mut self) {
        self.replay = true;
        self.line_no -= 1;
    }

    /// Reads the next line, of at most `limit` bytes, which must be UTF-8. An error only when the
    /// input cannot be read.
    pub(super) fn next(&mut self, limit: usize) -> std::io::Result<Line> {
        if std::mem::take(&mut self.replay) {
            self.line_no += 1;
            return Ok(Line::Text);
        }
        if self.discard_line {
            self.read_to_break(None)?;
            self.discard_line = false;
        }
        self.line.clear();
        let mut line = std::mem::take(&mut self.line);
        let outcome = self.read_to_break(Some((&mut line, limit)));
        self.line = line;
        let (any, over) = outcome?;
        if !any {
            return Ok(Line::End);
        }
        self.line_no += 1;
        if over {
            self.discard_line = true;
            return Ok(Line::Bad(format!("line longer than {limit} bytes")));
        }
        if std::str::from_utf8(&self.line).is_err() {
            return Ok(Line::Bad("not UTF-8 / ASCII text".to_owned()));
        }
        Ok(Line::Text)
    }

    /// Reads up to and including the next line break (or to the end of the input), keeping the bytes
    /// in `keep` up to its limit. Returns whether a line was there (any byte or a break) and whether it
    /// went over the limit (it then stops after `limit + 1` bytes of the line).
    fn read_to_break(
        &mut self,
        mut keep: Option<(&mut Vec<u8>, usize)>,
    ) -> std::io::Result<(bool, bool)> {
        let mut any = false;
        loop {
            let buf = match self.reader.fill_buf() {
                Ok(buf) => buf,
                Err(err) if err.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(err) => return Err(err),
            };
            if buf.is_empty() {
                return Ok((any, false));
            }
            let skip = usize::from(std::mem::take(&mut self.after_cr) && buf[0] == b'\n');
            let rest = &buf[skip..];
            let found = rest.iter().position(|&b| b == b'\n' || b == b'\r');
            let content = &rest[..found.unwrap_or(rest.len())];
            any |= !content.is_empty() || found.is_some();
            if let Some((line, limit)) = keep.as_mut() {
                let room = *limit - line.len();
                if content.len() > room {
                    // Over the limit: the rest of the line stays unread, for the caller to drop.
                    self.reader.consume(skip + room + 1);
                    return Ok((true, true));
                }
                line.extend_from_slice(content);
            }
            match found {
                Some(at) => {
                    self.after_cr = rest[at] == b'\r';
                    self.reader.consume(skip + at + 1);
                    return Ok((true, false));
                }
                None => {
                    let used = buf.len();
                    self.reader.consume(used);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Every line of `input` read with `limit`: `Ok(text)` or `Err(why)`, with its number.
    fn lines(input: &[u8], limit: usize) -> Vec<(usize, Result<String, String>)> {
        let mut reader = LineReader::new(input);
        let mut out = Vec::new();
        loop {
            let line = match reader.next(limit).unwrap() {
                Line::End => return out,
                Line::Text => Ok(reader.text().to_owned()),
                Line::Bad(why) => Err(why),
            };
            out.push((reader.line_no(), line));
        }
    }

    #[test]
    fn breaks_as_numbered_lines_does() {
        let text = "a\r\nb\nc\rd\r\n\r\ne";
        let ours: Vec<(usize, String)> = lines(text.as_bytes(), usize::MAX)
            .into_iter()
            .map(|(n, l)| (n, l.unwrap()))
            .collect();
        let whole: Vec<(usize, String)> = crate::textutil::numbered_lines(text)
            .into_iter()
            .map(|(n, l)| (n, l.to_owned()))
            .collect();
        assert_eq!(ours, whole);
        for text in ["x\n", "x\r", "x\r\n", "", "\n", "\r\r\n\n", "a\n\rb"] {
            let ours: Vec<usize> = lines(text.as_bytes(), 8).iter().map(|l| l.0).collect();
            let whole: Vec<usize> = crate::textutil::numbered_lines(text)
                .iter()
                .map(|l| l.0)
                .collect();
            assert_eq!(ours, whole, "{text:?}");
        }
    }

    #[test]
    fn a_break_split_across_reads_is_one_break() {
        // A reader that hands over one byte at a time.
        let bytes = b"1,2\r\n3,4\r\n";
        let slow = std::io::BufReader::with_capacity(1, &bytes[..]);
        let mut reader = LineReader::new(slow);
        let mut got = Vec::new();
        while let Line::Text = reader.next(100).unwrap() {
            got.push((reader.line_no(), reader.text().to_owned()));
        }
        assert_eq!(got, [(1, "1,2".to_owned()), (2, "3,4".to_owned())]);
    }

    #[test]
    fn long_lines_and_bad_bytes_are_one_bad_line_each() {
        let got = lines(b"12345\n123456\r\nok\n\xff\nend", 5);
        assert_eq!(
            got,
            vec![
                (1, Ok("12345".to_owned())),
                (2, Err("line longer than 5 bytes".to_owned())),
                (3, Ok("ok".to_owned())),
                (4, Err("not UTF-8 / ASCII text".to_owned())),
                (5, Ok("end".to_owned())),
            ]
        );
    }
}

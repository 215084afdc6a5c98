//! Shared plumbing of the line-oriented text formats: line splitting with 1-based numbers,
//! typed token parsing with structured errors, and float formatting for the writers.

use std::path::Path;

use glam::DVec3;

use super::error::ParseError;

/// `text` with every `%XX` (two hex digits) replaced by the byte XX, as UTF-8 (URI
/// percent-decoding; `.skw` joint names); `None` for a malformed escape or invalid UTF-8.
pub fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%' {
            let hex = std::str::from_utf8(bytes.get(k + 1..k + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// How the writers print floating-point numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FloatFormat {
    /// Shortest text that reads back to the identical `f64` (default).
    #[default]
    RoundTrip,
    /// `printf("%.Nf")`-style fixed decimals (the paper tool writes 6).
    Fixed(usize),
}

impl FloatFormat {
    /// The tool's format: fixed with 6 decimals.
    pub const TOOL: FloatFormat = FloatFormat::Fixed(6);

    /// Formats `x`. Round-trip output uses plain decimals for moderate magnitudes and
    /// scientific notation outside `[1e-5, 1e16)`; both parse back bit-exactly.
    pub fn format(self, x: f64) -> String {
        match self {
            FloatFormat::RoundTrip => {
                let a = x.abs();
                if a == 0.0 || (1e-5..1e16).contains(&a) || !a.is_finite() {
                    format!("{x}")
                } else {
                    format!("{x:e}")
                }
            }
            FloatFormat::Fixed(decimals) => format!("{x:.decimals$}"),
        }
    }

    /// Formats `x`, refusing a non-finite value: no writer ever writes NaN or ±inf.
    pub fn checked(self, x: f64) -> std::io::Result<String> {
        if x.is_finite() {
            Ok(self.format(x))
        } else {
            Err(non_finite_output(&format!("the value {x}")))
        }
    }

    /// The components of `vectors` (x, y, z of each in turn), formatted and separated by single
    /// spaces.
    pub fn vectors(self, vectors: &[DVec3]) -> String {
        let mut text = String::new();
        for x in vectors.iter().flat_map(|v| v.to_array()) {
            if !text.is_empty() {
                text.push(' ');
            }
            text += &self.format(x);
        }
        text
    }
}

/// The error of a writer asked to write a non-finite number (`what` names the element).
pub fn non_finite_output(what: &str) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("refusing to write {what}: it is not a finite number"),
    )
}

/// One non-empty source line.
pub(crate) struct Line<'a> {
    pub source: &'a Path,
    /// 1-based line number.
    pub number: usize,
    pub text: &'a str,
}

/// Iterates the lines of `data` (split on `\n`, trailing `\r` removed), checking UTF-8 per line.
pub(crate) fn lines<'a>(
    data: &'a [u8],
    source: &'a Path,
) -> impl Iterator<Item = Result<Line<'a>, ParseError>> + 'a {
    // A UTF-8 byte-order mark (some Windows editors write one) is not part of the first line.
    let data = data.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(data);
    // A final newline ends the last line; it does not start another one.
    let data = data.strip_suffix(b"\n").unwrap_or(data);
    let mut parts = data.split(|&b| b == b'\n');
    let mut number = 0usize;
    std::iter::from_fn(move || {
        let raw = parts.next()?;
        number += 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        Some(match std::str::from_utf8(raw) {
            Ok(text) => Ok(Line {
                source,
                number,
                text,
            }),
            Err(_) => Err(ParseError::InvalidUtf8 {
                path: source.to_path_buf(),
                line: number,
            }),
        })
    })
}

impl<'a> Line<'a> {
    /// True for lines with no tokens or whose first token starts with `#`.
    pub fn is_blank_or_comment(&self) -> bool {
        match self.text.split_whitespace().next() {
            None => true,
            Some(t) => t.starts_with('#'),
        }
    }

    pub fn tokens(&self) -> Tokens<'a> {
        Tokens {
            source: self.source,
            number: self.number,
            iter: self.text.split_whitespace(),
        }
    }

    pub fn malformed(&self, expected: impl Into<String>, found: impl Into<String>) -> ParseError {
        ParseError::Malformed {
            path: self.source.to_path_buf(),
            line: self.number,
            expected: expected.into(),
            found: found.into(),
        }
    }

    pub fn invalid(&self, message: impl Into<String>) -> ParseError {
        ParseError::Invalid {
            path: self.source.to_path_buf(),
            line: self.number,
            message: message.into(),
        }
    }

    pub fn out_of_range(&self, what: &'static str, index: i64, len: usize) -> ParseError {
        ParseError::IndexOutOfRange {
            path: self.source.to_path_buf(),
            line: self.number,
            what,
            index,
            len,
        }
    }
}

/// The whitespace-separated tokens of one line, parsed on demand.
pub(crate) struct Tokens<'a> {
    source: &'a Path,
    number: usize,
    iter: std::str::SplitWhitespace<'a>,
}

impl<'a> Tokens<'a> {
    fn error(&self, expected: &str, found: &str) -> ParseError {
        ParseError::Malformed {
            path: self.source.to_path_buf(),
            line: self.number,
            expected: expected.to_string(),
            found: found.to_string(),
        }
    }

    /// The next token as text, or a "found end of line" error.
    pub fn text(&mut self, what: &str) -> Result<&'a str, ParseError> {
        self.iter
            .next()
            .ok_or_else(|| self.error(what, "end of line"))
    }

    /// The next token, which must be a finite number of magnitude at most
    /// [`crate::error::MAX_INPUT_MAGNITUDE`] (so that no sum or product of the method overflows).
    pub fn f64(&mut self, what: &str) -> Result<f64, ParseError> {
        let t = self.text(what)?;
        match t.parse::<f64>() {
            Ok(x) if crate::error::is_input_value(x) => Ok(x),
            _ => Err(self.error(
                &format!("{what} (a finite number of magnitude at most 1e12)"),
                t,
            )),
        }
    }

    /// The next token, which must be a non-negative integer.
    pub fn usize(&mut self, what: &str) -> Result<usize, ParseError> {
        let t = self.text(what)?;
        t.parse::<usize>()
            .map_err(|_| self.error(&format!("{what} (a non-negative integer)"), t))
    }

    /// The next token, which must be an integer.
    pub fn i64(&mut self, what: &str) -> Result<i64, ParseError> {
        let t = self.text(what)?;
        t.parse::<i64>()
            .map_err(|_| self.error(&format!("{what} (an integer)"), t))
    }

    /// Three finite numbers.
    pub fn vec3(&mut self, what: &str) -> Result<glam::DVec3, ParseError> {
        Ok(glam::DVec3::new(
            self.f64(what)?,
            self.f64(what)?,
            self.f64(what)?,
        ))
    }

    /// Requires that no token is left.
    pub fn end(mut self) -> Result<(), ParseError> {
        match self.iter.next() {
            None => Ok(()),
            Some(t) => Err(self.error("end of line", t)),
        }
    }

    pub fn next_raw(&mut self) -> Option<&'a str> {
        self.iter.next()
    }

    /// The remaining tokens, unparsed.
    pub fn rest(&mut self) -> &mut std::str::SplitWhitespace<'a> {
        &mut self.iter
    }
}

/// Parses `<a> <b> <weight>` triplet files (skw, cage weights, CoR weights): blank lines and
/// `#` comments are skipped; every other line must hold two non-negative integers and a finite
/// number. `f` receives the line (for errors) and the three values.
pub(crate) fn for_each_triplet(
    data: &[u8],
    source: &Path,
    names: [&str; 3],
    mut f: impl FnMut(&Line<'_>, usize, usize, f64) -> Result<(), ParseError>,
) -> Result<(), ParseError> {
    for line in lines(data, source) {
        let line = line?;
        if line.is_blank_or_comment() {
            continue;
        }
        let mut t = line.tokens();
        let a = t.usize(names[0])?;
        let b = t.usize(names[1])?;
        let w = t.f64(names[2])?;
        t.end()?;
        f(&line, a, b, w)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding_reads_escapes_and_refuses_malformed_ones() {
        assert_eq!(percent_decode("a%20b%25").as_deref(), Some("a b%"));
        assert_eq!(percent_decode("%C3%A9t%C3%A9").as_deref(), Some("été"));
        assert_eq!(percent_decode("plain").as_deref(), Some("plain"));
        assert_eq!(percent_decode("50%"), None);
        assert_eq!(percent_decode("%zz"), None);
        assert_eq!(percent_decode("%FF"), None);
    }

    #[test]
    fn round_trip_format_is_exact() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.1,
            -1.5e-7,
            123456.789,
            1e300,
            f64::MIN_POSITIVE,
            5e-324,
            (-27.711_649_f64).next_up(),
            f64::MAX,
        ] {
            let s = FloatFormat::RoundTrip.format(x);
            let y: f64 = s.parse().unwrap();
            assert_eq!(x.to_bits(), y.to_bits(), "{x} -> {s}");
        }
        assert_eq!(FloatFormat::RoundTrip.format(1e-7), "1e-7");
        assert_eq!(FloatFormat::TOOL.format(0.5), "0.500000");
    }

    #[test]
    fn numbers_past_the_input_bound_are_rejected_with_line_and_value() {
        let src = Path::new("mem");
        for (text, ok) in [
            ("1e12", true),
            ("-1e12", true),
            ("1.0000001e12", false),
            ("1e308", false),
            ("-1e308", false),
            ("inf", false),
            ("NaN", false),
        ] {
            let line = lines(text.as_bytes(), src).next().unwrap().unwrap();
            let got = line.tokens().f64("weight");
            assert_eq!(got.is_ok(), ok, "{text}");
            if let Err(e) = got {
                assert!(
                    matches!(&e, ParseError::Malformed { line: 1, found, .. } if found == text),
                    "{e}"
                );
            }
        }
        assert!(FloatFormat::RoundTrip.checked(f64::NAN).is_err());
        assert!(FloatFormat::TOOL.checked(f64::NEG_INFINITY).is_err());
        assert_eq!(FloatFormat::RoundTrip.checked(0.5).unwrap(), "0.5");
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let src = Path::new("mem");
        let first = lines(b"\xEF\xBB\xBF12 0 0.5\n", src)
            .next()
            .unwrap()
            .unwrap();
        assert_eq!(first.text, "12 0 0.5");
        assert_eq!(first.tokens().usize("joint").unwrap(), 12);
    }

    #[test]
    fn line_numbers_and_utf8() {
        let src = Path::new("mem");
        let data = b"a\r\n\nb\xff\n";
        let got: Vec<_> = lines(data, src).collect();
        assert_eq!(got[0].as_ref().unwrap().text, "a");
        assert_eq!(got[1].as_ref().unwrap().number, 2);
        assert!(matches!(
            got[2],
            Err(ParseError::InvalidUtf8 { line: 3, .. })
        ));
    }
}

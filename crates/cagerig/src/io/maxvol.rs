//! MaxVol row selection `<cage>.maxvol`: `MAXVOLSELECTION <n>` then `n` mesh-vertex indices
//! (0-based), separated by any whitespace including newlines (read like `fscanf`).

use std::io::Write;
use std::path::Path;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::lines;

/// Reads the selected mesh rows; each must be `< num_vertices` and appear once.
pub fn read_maxvol(path: &Path, num_vertices: usize) -> Result<Vec<usize>, ParseError> {
    parse_maxvol(&read_file(path)?, path, num_vertices)
}

/// Parses MaxVol text.
pub fn parse_maxvol(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
) -> Result<Vec<usize>, ParseError> {
    let mut expected: Option<usize> = None;
    let mut header_seen = false;
    let mut rows = Vec::new();
    let mut seen = vec![false; num_vertices];
    let mut last_line = 0;
    for line in lines(data, source) {
        let line = line?;
        last_line = line.number;
        let mut tokens = line.tokens();
        if !header_seen {
            match tokens.next_raw() {
                None => continue,
                Some("MAXVOLSELECTION") => header_seen = true,
                Some(other) => return Err(line.malformed("MAXVOLSELECTION", other)),
            }
        }
        if expected.is_none() {
            match tokens.next_raw() {
                None => continue,
                Some(t) => match t.parse::<usize>() {
                    Ok(n) => expected = Some(n),
                    Err(_) => {
                        return Err(line.malformed("the row count (a non-negative integer)", t));
                    }
                },
            }
        }
        let n = expected.unwrap_or(0);
        while let Some(t) = tokens.next_raw() {
            if rows.len() == n {
                return Err(line.malformed(format!("end of file after {n} rows"), t));
            }
            let row: usize = t
                .parse()
                .map_err(|_| line.malformed("a mesh vertex index (a non-negative integer)", t))?;
            if row >= num_vertices {
                return Err(line.out_of_range("mesh vertex", row as i64, num_vertices));
            }
            if std::mem::replace(&mut seen[row], true) {
                return Err(line.invalid(format!("mesh vertex {row} is selected twice")));
            }
            rows.push(row);
        }
    }
    let number = last_line.max(1);
    match expected {
        None => Err(ParseError::Malformed {
            path: source.to_path_buf(),
            line: number,
            expected: "MAXVOLSELECTION <n>".into(),
            found: "end of file".into(),
        }),
        Some(n) if rows.len() != n => Err(ParseError::Malformed {
            path: source.to_path_buf(),
            line: number,
            expected: format!("{n} rows"),
            found: format!("{} rows", rows.len()),
        }),
        Some(_) => Ok(rows),
    }
}

/// Writes a MaxVol selection, replacing `path` atomically.
pub fn write_maxvol(path: &Path, rows: &[usize]) -> Result<(), ParseError> {
    write_atomically(path, |w| write_maxvol_to(w, rows))
}

/// Writes MaxVol text to any writer.
pub fn write_maxvol_to(w: &mut dyn Write, rows: &[usize]) -> std::io::Result<()> {
    writeln!(w, "MAXVOLSELECTION {}", rows.len())?;
    for r in rows {
        write!(w, "{r} ")?;
    }
    writeln!(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_across_lines_and_round_trips() {
        let p = Path::new("m.maxvol");
        let rows = parse_maxvol(b"MAXVOLSELECTION\n3 4\n0\n\n2 ", p, 5).unwrap();
        assert_eq!(rows, vec![4, 0, 2]);
        let mut out = Vec::new();
        write_maxvol_to(&mut out, &rows).unwrap();
        assert_eq!(parse_maxvol(&out, p, 5).unwrap(), rows);
    }

    #[test]
    fn errors_name_the_line() {
        let p = Path::new("m.maxvol");
        let e = parse_maxvol(b"MAXVOL 3\n", p, 5).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 1, .. }));
        let e = parse_maxvol(b"MAXVOLSELECTION 2\n1\n9\n", p, 5).unwrap_err();
        assert!(matches!(
            e,
            ParseError::IndexOutOfRange {
                line: 3,
                index: 9,
                ..
            }
        ));
        let e = parse_maxvol(b"MAXVOLSELECTION 2\n1 1\n", p, 5).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 2, .. }));
        let e = parse_maxvol(b"MAXVOLSELECTION 3\n1 2\n", p, 5).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 2, .. }));
        let e = parse_maxvol(b"MAXVOLSELECTION 1\n1 2\n", p, 5).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 2, .. }));
        let e = parse_maxvol(b"", p, 5).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 1, .. }));
    }
}

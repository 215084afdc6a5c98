//! Cage coordinates file `<cage>_cageWeights.txt` (Φ, `#V × #C`): lines
//! `<cageVertex> <meshVertex> <weight>`; missing pairs are 0, weights may be negative.

use std::io::Write;
use std::path::Path;

use faer::Mat;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::{FloatFormat, for_each_triplet};
use crate::cage_coords::CageCoords;

/// Reads Φ for `num_vertices` mesh vertices and `num_cage_vertices` cage vertices.
pub fn read_cage_weights(
    path: &Path,
    num_vertices: usize,
    num_cage_vertices: usize,
) -> Result<CageCoords, ParseError> {
    parse_cage_weights(&read_file(path)?, path, num_vertices, num_cage_vertices)
}

/// Parses cage-weights text. A pair listed twice is an error (the tool silently keeps the last).
pub fn parse_cage_weights(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
    num_cage_vertices: usize,
) -> Result<CageCoords, ParseError> {
    let mut matrix = Mat::<f64>::zeros(num_vertices, num_cage_vertices);
    let mut seen = vec![false; num_vertices * num_cage_vertices];
    for_each_triplet(
        data,
        source,
        ["cage vertex index", "mesh vertex index", "weight"],
        |line, cage_vertex, vertex, weight| {
            if cage_vertex >= num_cage_vertices {
                return Err(line.out_of_range(
                    "cage vertex",
                    cage_vertex as i64,
                    num_cage_vertices,
                ));
            }
            if vertex >= num_vertices {
                return Err(line.out_of_range("mesh vertex", vertex as i64, num_vertices));
            }
            let slot = &mut seen[cage_vertex * num_vertices + vertex];
            if *slot {
                return Err(line.invalid(format!(
                    "duplicate weight for cage vertex {cage_vertex}, mesh vertex {vertex}"
                )));
            }
            *slot = true;
            matrix[(vertex, cage_vertex)] = weight;
            Ok(())
        },
    )?;
    CageCoords::from_matrix(matrix).map_err(|e| ParseError::Rig {
        path: source.to_path_buf(),
        source: e,
    })
}

/// Writes every pair of Φ (grouped by mesh vertex, cage vertex ascending), replacing `path`
/// atomically. [`FloatFormat::TOOL`] reproduces the tool's 6 decimals.
pub fn write_cage_weights(
    path: &Path,
    coords: &CageCoords,
    format: FloatFormat,
) -> Result<(), ParseError> {
    write_atomically(path, |w| write_cage_weights_to(w, coords, format))
}

/// Writes cage-weights text to any writer.
pub fn write_cage_weights_to(
    w: &mut dyn Write,
    coords: &CageCoords,
    format: FloatFormat,
) -> std::io::Result<()> {
    for i in 0..coords.num_vertices() {
        for k in 0..coords.num_cage_vertices() {
            writeln!(w, "{k} {i} {}", format.checked(coords.get(i, k))?)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_cage_then_mesh_columns_missing_is_zero() {
        let p = Path::new("w.txt");
        let c = parse_cage_weights(b"0 0 0.25\n1 0 0.75\n1 2 -0.5\n", p, 3, 2).unwrap();
        assert_eq!(c.get(0, 0), 0.25);
        assert_eq!(c.get(0, 1), 0.75);
        assert_eq!(c.get(2, 1), -0.5);
        assert_eq!(c.get(1, 0), 0.0);
        let mut out = Vec::new();
        write_cage_weights_to(&mut out, &c, FloatFormat::RoundTrip).unwrap();
        assert_eq!(String::from_utf8(out.clone()).unwrap().lines().count(), 6);
        assert_eq!(parse_cage_weights(&out, p, 3, 2).unwrap(), c);
        let mut fixed = Vec::new();
        write_cage_weights_to(&mut fixed, &c, FloatFormat::TOOL).unwrap();
        assert!(
            String::from_utf8(fixed)
                .unwrap()
                .starts_with("0 0 0.250000\n1 0 0.750000\n")
        );
    }

    #[test]
    fn errors_name_the_line() {
        let p = Path::new("w.txt");
        let e = parse_cage_weights(b"0 0 1\n2 0 1\n", p, 1, 2).unwrap_err();
        assert!(matches!(
            e,
            ParseError::IndexOutOfRange {
                line: 2,
                what: "cage vertex",
                ..
            }
        ));
        let e = parse_cage_weights(b"0 0 1\n0 0 1\n", p, 1, 2).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 2, .. }));
        let e = parse_cage_weights(b"0 0 1\n1 0 inf\n", p, 1, 2).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 2, .. }));
    }
}

//! Centre-of-rotation weights `<mesh>_corWeights.txt` (S, `#V × #V`): lines
//! `<meshVertex i> <meshVertex k> <weight>` (note: the row index comes FIRST here) meaning
//! CoR_i = Σ_k S[i,k] · M_rest[k].

use std::io::Write;
use std::path::Path;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::{FloatFormat, for_each_triplet};
use crate::sparse_rows::SparseRows;

/// Reads S for a mesh of `num_vertices` vertices. Duplicate pairs are summed.
pub fn read_cor_weights(path: &Path, num_vertices: usize) -> Result<SparseRows, ParseError> {
    parse_cor_weights(&read_file(path)?, path, num_vertices)
}

/// Parses CoR-weights text.
pub fn parse_cor_weights(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
) -> Result<SparseRows, ParseError> {
    let mut triplets = Vec::new();
    for_each_triplet(
        data,
        source,
        ["mesh vertex index i", "mesh vertex index k", "weight"],
        |line, i, k, weight| {
            for index in [i, k] {
                if index >= num_vertices {
                    return Err(line.out_of_range("mesh vertex", index as i64, num_vertices));
                }
            }
            triplets.push((i, k, weight));
            Ok(())
        },
    )?;
    SparseRows::from_triplets(num_vertices, num_vertices, triplets).map_err(|e| ParseError::Rig {
        path: source.to_path_buf(),
        source: e,
    })
}

/// Writes S (row-major, `i k w`), replacing `path` atomically.
pub fn write_cor_weights(
    path: &Path,
    weights: &SparseRows,
    format: FloatFormat,
) -> Result<(), ParseError> {
    write_atomically(path, |w| write_cor_weights_to(w, weights, format))
}

/// Writes CoR-weights text to any writer.
pub fn write_cor_weights_to(
    w: &mut dyn Write,
    weights: &SparseRows,
    format: FloatFormat,
) -> std::io::Result<()> {
    for (i, k, x) in weights.triplets() {
        writeln!(w, "{i} {k} {}", format.checked(x)?)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn row_index_comes_first() {
        let p = Path::new("c.txt");
        let s = parse_cor_weights(b"0 1 0.5\n0 2 0.5\n2 2 1\n", p, 3).unwrap();
        let m = [DVec3::X, DVec3::Y, DVec3::Z];
        let mut cor = [DVec3::ZERO; 3];
        s.apply(&m, &mut cor);
        assert_eq!(cor[0], DVec3::new(0.0, 0.5, 0.5));
        assert_eq!(cor[1], DVec3::ZERO);
        assert_eq!(cor[2], DVec3::Z);
        let mut out = Vec::new();
        write_cor_weights_to(&mut out, &s, FloatFormat::RoundTrip).unwrap();
        assert_eq!(parse_cor_weights(&out, p, 3).unwrap(), s);
        let e = parse_cor_weights(b"0 1 0.5\n0 3 0.5\n", p, 3).unwrap_err();
        assert!(matches!(
            e,
            ParseError::IndexOutOfRange {
                line: 2,
                index: 3,
                ..
            }
        ));
    }
}

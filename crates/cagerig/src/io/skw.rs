//! Skinning weights `.skw` (Ω): one line per entry `<joint> <meshVertex> <weight>`; missing = 0.
//!
//! Unlike the paper tool, blank lines and `#` comments are skipped, duplicates are summed (and
//! reported) instead of being counted twice, explicit zeros are dropped, and rows are
//! renormalised to sum to 1 with a [`Warning`] (see [`SkinWeights::from_triplets`]).

use std::io::Write;
use std::path::Path;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::{FloatFormat, for_each_triplet};
use crate::error::Warning;
use crate::skin_weights::SkinWeights;

/// Reads Ω (`#V × #J`) for a mesh with `num_vertices` vertices and a skeleton of `num_joints`.
pub fn read_skw(
    path: &Path,
    num_vertices: usize,
    num_joints: usize,
) -> Result<(SkinWeights, Vec<Warning>), ParseError> {
    parse_skw(&read_file(path)?, path, num_vertices, num_joints)
}

/// Parses `.skw` text into `(vertex, joint, weight)` triplets, in file order, checking ranges
/// and that weights are finite and non-negative.
pub fn parse_skw_triplets(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
    num_joints: usize,
) -> Result<Vec<(usize, usize, f64)>, ParseError> {
    let mut triplets = Vec::new();
    for_each_triplet(
        data,
        source,
        ["joint index", "mesh vertex index", "weight"],
        |line, joint, vertex, weight| {
            if joint >= num_joints {
                return Err(line.out_of_range("joint", joint as i64, num_joints));
            }
            if vertex >= num_vertices {
                return Err(line.out_of_range("mesh vertex", vertex as i64, num_vertices));
            }
            if weight < 0.0 {
                return Err(line.invalid(format!(
                    "skinning weight {weight} is negative (vertex {vertex}, joint {joint})"
                )));
            }
            triplets.push((vertex, joint, weight));
            Ok(())
        },
    )?;
    Ok(triplets)
}

/// Parses `.skw` text into Ω (renormalised rows, with warnings).
pub fn parse_skw(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
    num_joints: usize,
) -> Result<(SkinWeights, Vec<Warning>), ParseError> {
    let triplets = parse_skw_triplets(data, source, num_vertices, num_joints)?;
    if triplets.is_empty() && num_vertices > 0 {
        return Err(ParseError::Rig {
            path: source.to_path_buf(),
            source: crate::error::RigError::Invalid(format!(
                "expected `<joint> <meshVertex> <weight>` lines for {num_vertices} vertices, \
                 found no weight: every vertex would stay at rest and the cage could not \
                 follow the skeleton"
            )),
        });
    }
    SkinWeights::from_triplets(num_vertices, num_joints, triplets).map_err(|e| ParseError::Rig {
        path: source.to_path_buf(),
        source: e,
    })
}

/// Writes Ω as `.skw` (grouped by vertex, joints ascending), replacing `path` atomically.
pub fn write_skw(
    path: &Path,
    weights: &SkinWeights,
    format: FloatFormat,
) -> Result<(), ParseError> {
    write_atomically(path, |w| write_skw_to(w, weights, format))
}

/// Writes `.skw` text to any writer.
pub fn write_skw_to(
    w: &mut dyn Write,
    weights: &SkinWeights,
    format: FloatFormat,
) -> std::io::Result<()> {
    for v in 0..weights.num_vertices() {
        let (joints, values) = weights.row(v);
        for (j, x) in joints.iter().zip(values) {
            writeln!(w, "{j} {v} {}", format.checked(*x)?)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_columns_joint_then_vertex_and_renormalises() {
        let (w, warnings) = parse_skw(
            b"0 1 0.5\n1 1 0.25\n\n# c\n2 0 1.0\n",
            Path::new("t.skw"),
            2,
            3,
        )
        .unwrap();
        assert_eq!(w.get(1, 0), 0.5 / 0.75);
        assert_eq!(w.get(0, 2), 1.0);
        assert!(matches!(
            warnings[0],
            Warning::WeightsRenormalised { rows: 1, .. }
        ));
        let mut out = Vec::new();
        write_skw_to(&mut out, &w, FloatFormat::RoundTrip).unwrap();
        let (back, _) = parse_skw(&out, Path::new("mem"), 2, 3).unwrap();
        assert_eq!(back, w);
    }

    #[test]
    fn errors_name_the_line() {
        let p = Path::new("t.skw");
        let e = parse_skw(b"0 0 1\n3 0 1\n", p, 1, 3).unwrap_err();
        assert!(matches!(
            e,
            ParseError::IndexOutOfRange {
                line: 2,
                what: "joint",
                index: 3,
                ..
            }
        ));
        let e = parse_skw(b"0 0 1\n0 1 1\n", p, 1, 3).unwrap_err();
        assert!(matches!(
            e,
            ParseError::IndexOutOfRange {
                line: 2,
                what: "mesh vertex",
                ..
            }
        ));
        let e = parse_skw(b"0 0 -1\n", p, 1, 3).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 1, .. }));
        let e = parse_skw(b"0 0 1 4\n", p, 1, 3).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 1, .. }));
        let e = parse_skw(b"0 0\n", p, 1, 3).unwrap_err();
        assert!(
            matches!(&e, ParseError::Malformed { line: 1, found, .. } if found == "end of line")
        );
    }
}

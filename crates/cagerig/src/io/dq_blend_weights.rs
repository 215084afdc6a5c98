//! Per-vertex DQ blend weights `<mesh>_dqBlendWeights.txt` (b, `#V`; cagerig's companion to the
//! paper tool's file set, for [`crate::skinning::SkinningMethod::Blended`]): lines
//! `<meshVertex i> <weight b_i>` with b_i in [0, 1]; vertex i is skinned (1 − b_i)·LBS + b_i·DQS
//! (Maya's "weight blended" skin clusters). Vertices not listed have b = 0 (pure LBS); `#` starts
//! a comment line.

use std::io::Write;
use std::path::Path;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::{FloatFormat, lines};
use crate::skinning::DqBlendWeights;

/// Reads the blend weights of a mesh of `num_vertices` vertices.
pub fn read_dq_blend_weights(
    path: &Path,
    num_vertices: usize,
) -> Result<DqBlendWeights, ParseError> {
    parse_dq_blend_weights(&read_file(path)?, path, num_vertices)
}

/// Parses DQ-blend-weights text: every listed vertex in range and listed once, every weight a
/// finite number in [0, 1].
pub fn parse_dq_blend_weights(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
) -> Result<DqBlendWeights, ParseError> {
    let mut values = vec![0.0; num_vertices];
    let mut listed = vec![false; num_vertices];
    for line in lines(data, source) {
        let line = line?;
        if line.is_blank_or_comment() {
            continue;
        }
        let mut tokens = line.tokens();
        let vertex = tokens.usize("a mesh vertex index")?;
        let weight = tokens.f64("a DQ blend weight")?;
        tokens.end()?;
        if vertex >= num_vertices {
            return Err(line.out_of_range("mesh vertex", vertex as i64, num_vertices));
        }
        if !(0.0..=1.0).contains(&weight) {
            return Err(line.malformed(
                "a DQ blend weight in [0, 1] (0: LBS, 1: DQS)",
                weight.to_string(),
            ));
        }
        if std::mem::replace(&mut listed[vertex], true) {
            return Err(line.invalid(format!("mesh vertex {vertex} is listed twice")));
        }
        values[vertex] = weight;
    }
    DqBlendWeights::new(values).map_err(|e| ParseError::Rig {
        path: source.to_path_buf(),
        source: e,
    })
}

/// Writes the non-zero blend weights (`i b_i`), replacing `path` atomically.
pub fn write_dq_blend_weights(
    path: &Path,
    weights: &DqBlendWeights,
    format: FloatFormat,
) -> Result<(), ParseError> {
    write_atomically(path, |w| write_dq_blend_weights_to(w, weights, format))
}

/// Writes DQ-blend-weights text to any writer.
pub fn write_dq_blend_weights_to(
    w: &mut dyn Write,
    weights: &DqBlendWeights,
    format: FloatFormat,
) -> std::io::Result<()> {
    writeln!(
        w,
        "# cagerig DQ blend weights: <mesh vertex> <b>, skinned (1 - b)·LBS + b·DQS; unlisted: b = 0"
    )?;
    for (i, &b) in weights.values().iter().enumerate() {
        if b != 0.0 {
            writeln!(w, "{i} {}", format.checked(b)?)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_leaves_unlisted_vertices_at_lbs() {
        let p = Path::new("arm_dqBlendWeights.txt");
        let b = parse_dq_blend_weights(b"# comment\n2 0.25\n0 1\n", p, 4).unwrap();
        assert_eq!(b.values(), &[1.0, 0.0, 0.25, 0.0]);
        let mut out = Vec::new();
        write_dq_blend_weights_to(&mut out, &b, FloatFormat::RoundTrip).unwrap();
        assert_eq!(parse_dq_blend_weights(&out, p, 4).unwrap(), b);
    }

    #[test]
    fn names_the_line_of_a_bad_entry() {
        let p = Path::new("b.txt");
        let out_of_range = parse_dq_blend_weights(b"0 0.5\n7 0.5\n", p, 4).unwrap_err();
        assert!(matches!(
            out_of_range,
            ParseError::IndexOutOfRange {
                line: 2,
                index: 7,
                ..
            }
        ));
        let above_one = parse_dq_blend_weights(b"1 1.5\n", p, 4).unwrap_err();
        assert!(above_one.to_string().contains("in [0, 1]"), "{above_one}");
        assert!(matches!(above_one, ParseError::Malformed { line: 1, .. }));
        let twice = parse_dq_blend_weights(b"1 0.5\n1 0.5\n", p, 4).unwrap_err();
        assert!(twice.to_string().contains("listed twice"), "{twice}");
        let missing = parse_dq_blend_weights(b"1\n", p, 4).unwrap_err();
        assert!(matches!(missing, ParseError::Malformed { line: 1, .. }));
    }
}

//! Wavefront OBJ: the character mesh M and the cage C.
//!
//! Reading keeps the vertices exactly in file order (companion files index them by position in
//! the file), parses `f` tokens `a`, `a/b`, `a//c`, `a/b/c` (1-based, negative = relative) and
//! fan-triangulates polygons: (0,1,2), (0,2,3), … (quads split like the paper tool; it drops
//! larger polygons, we keep them). `vt`, `vn`, groups, materials, lines and points are ignored.
//!
//! `tobj` is deliberately not used: it renumbers vertices in order of first use and drops
//! unreferenced ones (which would break every per-vertex companion file), reads `f32` unless a
//! feature is enabled, and reports errors without line numbers.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::{FloatFormat, lines};
use crate::mesh::TriMesh;

/// Reads an OBJ file into a triangle mesh (positions `#V` in file order, triangles `#F`).
pub fn read_obj(path: &Path) -> Result<TriMesh, ParseError> {
    parse_obj(&read_file(path)?, path)
}

/// Parses OBJ text; `source` names it in errors.
pub fn parse_obj(data: &[u8], source: &Path) -> Result<TriMesh, ParseError> {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    // Line number of the face each triangle came from, to name it if an index is out of range.
    let mut triangle_lines: Vec<usize> = Vec::new();
    let mut corners: Vec<i64> = Vec::new();
    for line in lines(data, source) {
        let line = line?;
        let mut tokens = line.tokens();
        match tokens.next_raw() {
            Some("v") => {
                let p = tokens.vec3("vertex coordinate")?;
                // Optional w or r g b: must still be numbers.
                while let Some(extra) = tokens.next_raw() {
                    if extra.parse::<f64>().is_err() {
                        return Err(line.malformed("a number or end of line", extra));
                    }
                }
                positions.push(p);
            }
            Some("f") => {
                corners.clear();
                for token in tokens.rest() {
                    let index_text = token.split('/').next().unwrap_or("");
                    let index: i64 = index_text.parse().map_err(|_| {
                        line.malformed("a vertex index (a, a/b, a//c or a/b/c)", token)
                    })?;
                    let zero_based = if index > 0 {
                        index - 1
                    } else if index < 0 {
                        // Relative to the vertices defined so far.
                        positions.len() as i64 + index
                    } else {
                        return Err(line.malformed("a non-zero vertex index", token));
                    };
                    if zero_based < 0 || zero_based > u32::MAX as i64 {
                        return Err(line.out_of_range("face vertex", index, positions.len()));
                    }
                    corners.push(zero_based);
                }
                if corners.len() < 3 {
                    return Err(line.malformed(
                        "at least 3 vertex indices",
                        format!("{} indices", corners.len()),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0] as u32, corners[k] as u32, corners[k + 1] as u32]);
                    triangle_lines.push(line.number);
                }
            }
            _ => {}
        }
    }
    // Forward references are legal in OBJ, so ranges are checked once all vertices are known.
    let len = positions.len();
    for (tri, &number) in triangles.iter().zip(&triangle_lines) {
        if let Some(&bad) = tri.iter().find(|&&i| i as usize >= len) {
            return Err(ParseError::IndexOutOfRange {
                path: source.to_path_buf(),
                line: number,
                what: "face vertex",
                index: bad as i64 + 1,
                len,
            });
        }
    }
    TriMesh::new(positions, triangles).map_err(|source_err| ParseError::Rig {
        path: source.to_path_buf(),
        source: source_err,
    })
}

/// Writes `v x y z` lines (shortest round-trip floats: reading the file back gives identical
/// `f64`s) then `f a b c` lines (1-based), replacing `path` atomically.
pub fn write_obj(
    path: &Path,
    positions: &[DVec3],
    triangles: &[[u32; 3]],
) -> Result<(), ParseError> {
    write_atomically(path, |w| {
        write_obj_to(w, positions, triangles, FloatFormat::RoundTrip)
    })
}

/// Writes OBJ text to any writer with the given float format.
pub fn write_obj_to(
    w: &mut dyn Write,
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    format: FloatFormat,
) -> std::io::Result<()> {
    for (k, p) in positions.iter().enumerate() {
        if !p.is_finite() {
            return Err(super::text::non_finite_output(&format!("vertex {k} ({p})")));
        }
        writeln!(
            w,
            "v {} {} {}",
            format.format(p.x),
            format.format(p.y),
            format.format(p.z)
        )?;
    }
    for [a, b, c] in triangles {
        writeln!(w, "f {} {} {}", *a as u64 + 1, *b as u64 + 1, *c as u64 + 1)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<TriMesh, ParseError> {
        parse_obj(s.as_bytes(), Path::new("test.obj"))
    }

    #[test]
    fn reads_all_face_token_forms_and_fans_polygons() {
        let m = parse(
            "# comment\nv 0 0 0\nv 1 0 0 1\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
             o thing\nf 1/1/1 2//1 3/1 4\nf -4 -2 -1\nf 1 2 3 4 1\n",
        )
        .unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(
            m.triangles,
            vec![
                [0, 1, 2],
                [0, 2, 3],
                [0, 2, 3],
                [0, 1, 2],
                [0, 2, 3],
                [0, 3, 0]
            ]
        );
    }

    #[test]
    fn keeps_file_vertex_order_including_unreferenced() {
        let m = parse("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 4 3 2\n").unwrap();
        assert_eq!(m.positions[0], DVec3::splat(9.0));
        assert_eq!(m.triangles, vec![[3, 2, 1]]);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap_err();
        assert!(
            matches!(
                e,
                ParseError::IndexOutOfRange {
                    line: 4,
                    index: 7,
                    len: 3,
                    ..
                }
            ),
            "{e}"
        );
        let e = parse("v 0 0 0\nv 1 x 0\n").unwrap_err();
        assert!(
            matches!(&e, ParseError::Malformed { line: 2, found, .. } if found == "x"),
            "{e}"
        );
        let e = parse("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err();
        assert_eq!(e.line(), Some(3));
        let e = parse("v 0 0 0\nf 0 1 1\n").unwrap_err();
        assert_eq!(e.line(), Some(2));
        let e = parse("v 0 0 nan\n").unwrap_err();
        assert_eq!(e.line(), Some(1));
        let e = parse("v 0 0 0\nf -5 1 1\n").unwrap_err();
        assert!(matches!(e, ParseError::IndexOutOfRange { line: 2, .. }));
    }

    #[test]
    fn refuses_to_write_non_finite_vertices() {
        let mut out = Vec::new();
        let e = write_obj_to(
            &mut out,
            &[DVec3::ZERO, DVec3::new(0.0, f64::NAN, 0.0)],
            &[],
            FloatFormat::RoundTrip,
        )
        .unwrap_err();
        assert!(e.to_string().contains("vertex 1"), "{e}");
    }

    #[test]
    fn write_then_read_is_bit_exact() {
        let positions = vec![
            DVec3::new((-27.711_649_f64).next_up(), 0.1, 1.0 / 3.0),
            DVec3::new(1e-300, -0.0, 6.02214076e11),
            DVec3::new(std::f64::consts::PI, -1e-7, 123_456_789.123_456_78),
        ];
        let triangles = vec![[0, 1, 2], [2, 1, 0]];
        let mut bytes = Vec::new();
        write_obj_to(&mut bytes, &positions, &triangles, FloatFormat::RoundTrip).unwrap();
        let m = parse_obj(&bytes, Path::new("mem")).unwrap();
        assert_eq!(m.triangles, triangles);
        for (a, b) in m.positions.iter().zip(&positions) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
    }
}

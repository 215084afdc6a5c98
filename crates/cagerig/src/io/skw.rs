//! Skinning weights `.skw` (Ω): one line per entry `<joint> <meshVertex> <weight>`; missing = 0.
//!
//! Unlike the paper tool, blank lines and `#` comments are skipped, duplicates are summed (and
//! reported) instead of being counted twice, explicit zeros are dropped, and rows are
//! renormalised to sum to 1 with a [`Warning`] (see [`SkinWeights::from_triplets`]).
//!
//! The file may say which skeleton it was made for: a comment line
//! `# joints (<count>): <name 0> <name 1> …` (cagerig writes it; in a name, `%`, whitespace and
//! control characters are written as `%XX` UTF-8 bytes, and an empty name as `%`). When it is
//! there, reading checks it against the rig's skeleton: the joint count always, the names when
//! the skeleton is given ([`read_skw_for_skeleton`]). Files without it (the paper tool's) read as
//! before: only the joint indices are checked.

use std::io::Write;
use std::path::Path;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::text::{FloatFormat, for_each_triplet, lines};
use crate::error::Warning;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;

/// The start of the comment line that names the skeleton's joints.
const JOINTS_HEADER: &str = "# joints (";

/// Reads Ω (`#V × #J`) for a mesh with `num_vertices` vertices and a skeleton of `num_joints`
/// (a joints header, if the file has one, must list `num_joints` joints).
pub fn read_skw(
    path: &Path,
    num_vertices: usize,
    num_joints: usize,
) -> Result<(SkinWeights, Vec<Warning>), ParseError> {
    parse_skw(&read_file(path)?, path, num_vertices, num_joints)
}

/// Reads Ω for a mesh with `num_vertices` vertices bound to `skeleton`; `skeleton_source` names
/// the skeleton in errors (its file). A joints header, if the file has one, must list the
/// skeleton's joints, by count and by name.
pub fn read_skw_for_skeleton(
    path: &Path,
    num_vertices: usize,
    skeleton: &Skeleton,
    skeleton_source: &str,
) -> Result<(SkinWeights, Vec<Warning>), ParseError> {
    parse_skw_for_skeleton(
        &read_file(path)?,
        path,
        num_vertices,
        skeleton,
        skeleton_source,
    )
}

/// The joints a `.skw` says it was made for (its `# joints (<count>): …` line).
#[derive(Debug, Clone, PartialEq)]
pub struct SkwJoints {
    /// The 1-based line of the header.
    pub line: usize,
    /// The joint names, in joint index order.
    pub names: Vec<String>,
}

/// The joints header of `.skw` text, if it has one (the first such line).
pub fn skw_joints(data: &[u8], source: &Path) -> Result<Option<SkwJoints>, ParseError> {
    for line in lines(data, source) {
        let line = line?;
        let Some(rest) = line.text.trim_start().strip_prefix(JOINTS_HEADER) else {
            continue;
        };
        let expected = "`# joints (<count>): <name> …` with <count> names";
        let Some((count, names)) = rest.split_once("):") else {
            return Err(line.malformed(expected, line.text));
        };
        let count: usize = count
            .trim()
            .parse()
            .map_err(|_| line.malformed(expected, line.text))?;
        let names = names
            .split_whitespace()
            .map(decode_name)
            .collect::<Option<Vec<String>>>()
            .ok_or_else(|| {
                line.malformed("joint names with `%XX` escapes of UTF-8 bytes", line.text)
            })?;
        if names.len() != count {
            return Err(line.malformed(
                format!("{count} joint names after `# joints ({count}):`"),
                format!("{} names", names.len()),
            ));
        }
        return Ok(Some(SkwJoints {
            line: line.number,
            names,
        }));
    }
    Ok(None)
}

/// A joint name as one header token: `%`, whitespace and control characters as `%XX` UTF-8
/// bytes, an empty name as `%`.
fn encode_name(name: &str) -> String {
    if name.is_empty() {
        return "%".to_string();
    }
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        if c == '%' || c.is_whitespace() || c.is_control() {
            let mut buf = [0u8; 4];
            for b in c.encode_utf8(&mut buf).bytes() {
                out.push_str(&format!("%{b:02X}"));
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// The inverse of [`encode_name`]; `None` for a malformed escape.
fn decode_name(token: &str) -> Option<String> {
    if token == "%" {
        return Some(String::new());
    }
    super::text::percent_decode(token)
}

/// The first names of a joint list, for messages.
fn some_names(names: &[&str]) -> String {
    const SHOWN: usize = 5;
    let mut text = names
        .iter()
        .take(SHOWN)
        .copied()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        text.push_str(", …");
    }
    text
}

/// Refuses a header whose joint count is not `num_joints`; `skeleton` names the rig's skeleton
/// (its file), when known.
fn check_joint_count(
    header: &SkwJoints,
    source: &Path,
    num_joints: usize,
    skeleton: Option<&str>,
) -> Result<(), ParseError> {
    if header.names.len() == num_joints {
        return Ok(());
    }
    let names: Vec<&str> = header.names.iter().map(String::as_str).collect();
    Err(ParseError::Invalid {
        path: source.to_path_buf(),
        line: header.line,
        message: format!(
            "the weights were made for a skeleton of {} joints ({}), but the rig's skeleton{} \
             has {num_joints} joints: give the skeleton the weights were made for (--skeleton \
             FILE.skt), or compute weights for this skeleton (cagerig weights)",
            names.len(),
            some_names(&names),
            skeleton.map(|s| format!(" ({s})")).unwrap_or_default(),
        ),
    })
}

/// Parses `.skw` text for a mesh bound to `skeleton` (see [`read_skw_for_skeleton`]).
pub fn parse_skw_for_skeleton(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
    skeleton: &Skeleton,
    skeleton_source: &str,
) -> Result<(SkinWeights, Vec<Warning>), ParseError> {
    if let Some(header) = skw_joints(data, source)? {
        check_joint_count(&header, source, skeleton.len(), Some(skeleton_source))?;
        let differing = header
            .names
            .iter()
            .zip(skeleton.joints())
            .position(|(name, joint)| *name != joint.name);
        if let Some(j) = differing {
            return Err(ParseError::Invalid {
                path: source.to_path_buf(),
                line: header.line,
                message: format!(
                    "the weights were made for another skeleton: their joint {j} is {:?}, joint \
                     {j} of the rig's skeleton ({skeleton_source}) is {:?}: give the skeleton \
                     the weights were made for (--skeleton FILE.skt), or compute weights for \
                     this skeleton (cagerig weights)",
                    header.names[j],
                    skeleton.joint(j).name
                ),
            });
        }
    }
    parse_skw_unchecked_header(data, source, num_vertices, skeleton.len())
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

/// Parses `.skw` text into Ω (renormalised rows, with warnings); a joints header must list
/// `num_joints` joints.
pub fn parse_skw(
    data: &[u8],
    source: &Path,
    num_vertices: usize,
    num_joints: usize,
) -> Result<(SkinWeights, Vec<Warning>), ParseError> {
    if let Some(header) = skw_joints(data, source)? {
        check_joint_count(&header, source, num_joints, None)?;
    }
    parse_skw_unchecked_header(data, source, num_vertices, num_joints)
}

fn parse_skw_unchecked_header(
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

/// Writes Ω as `.skw` for `skeleton` (the joints header, then the entries grouped by vertex,
/// joints ascending), replacing `path` atomically. Fails if Ω has not one column per joint.
pub fn write_skw(
    path: &Path,
    weights: &SkinWeights,
    skeleton: &Skeleton,
    format: FloatFormat,
) -> Result<(), ParseError> {
    if weights.num_joints() != skeleton.len() {
        return Err(ParseError::Unrepresentable {
            path: path.to_path_buf(),
            message: format!(
                "the weights have {} joint columns, the skeleton has {} joints",
                weights.num_joints(),
                skeleton.len()
            ),
        });
    }
    write_atomically(path, |w| write_skw_to(w, weights, skeleton, format))
}

/// Writes `.skw` text for `skeleton` to any writer.
pub fn write_skw_to(
    w: &mut dyn Write,
    weights: &SkinWeights,
    skeleton: &Skeleton,
    format: FloatFormat,
) -> std::io::Result<()> {
    if weights.num_joints() != skeleton.len() {
        return Err(std::io::Error::other(format!(
            "the weights have {} joint columns, the skeleton has {} joints",
            weights.num_joints(),
            skeleton.len()
        )));
    }
    write!(w, "{JOINTS_HEADER}{}):", skeleton.len())?;
    for joint in skeleton.joints() {
        write!(w, " {}", encode_name(&joint.name))?;
    }
    writeln!(w)?;
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
        write_skw_to(
            &mut out,
            &w,
            &skeleton(&["a", "b", "c"]),
            FloatFormat::RoundTrip,
        )
        .unwrap();
        let (back, _) = parse_skw(&out, Path::new("mem"), 2, 3).unwrap();
        assert_eq!(back, w);
    }

    fn skeleton(names: &[&str]) -> Skeleton {
        Skeleton::new(
            names
                .iter()
                .enumerate()
                .map(|(j, name)| crate::skeleton::Joint {
                    name: (*name).to_string(),
                    parent: j.checked_sub(1),
                    rest_world_from_joint: glam::DAffine3::IDENTITY,
                })
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn the_joints_header_is_written_and_checked_against_the_skeleton() {
        let names = ["root", "odd name", "100%", ""];
        let s = skeleton(&names);
        let (w, _) = parse_skw(b"0 0 1\n3 1 1\n", Path::new("t.skw"), 2, 4).unwrap();
        let mut out = Vec::new();
        write_skw_to(&mut out, &w, &s, FloatFormat::RoundTrip).unwrap();
        let text = String::from_utf8(out.clone()).unwrap();
        assert!(
            text.starts_with("# joints (4): root odd%20name 100%25 %\n"),
            "{text}"
        );
        let header = skw_joints(&out, Path::new("t.skw")).unwrap().unwrap();
        assert_eq!(header.line, 1);
        assert_eq!(header.names, names);
        let (back, _) = parse_skw_for_skeleton(&out, Path::new("t.skw"), 2, &s, "s.skt").unwrap();
        assert_eq!(back, w);

        // Another joint count: refused, naming both counts and both files.
        let five = skeleton(&["a", "b", "c", "d", "e"]);
        let e = parse_skw_for_skeleton(&out, Path::new("t.skw"), 2, &five, "five.skt")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.skw:1: the weights were made for a skeleton of 4 joints")
                && e.contains("(five.skt) has 5 joints"),
            "{e}"
        );
        let e = parse_skw(&out, Path::new("t.skw"), 2, 5)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("of 4 joints") && e.contains("has 5 joints"),
            "{e}"
        );

        // The same count, another name: the first differing joint is named.
        let other = skeleton(&["root", "odd name", "elbow", ""]);
        let e = parse_skw_for_skeleton(&out, Path::new("t.skw"), 2, &other, "o.skt")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("joint 2 is \"100%\", joint 2 of the rig's skeleton (o.skt) is \"elbow\""),
            "{e}"
        );

        // A file without the header reads as before; a malformed header is refused.
        assert!(parse_skw_for_skeleton(b"0 0 1\n3 1 1\n", Path::new("t.skw"), 2, &s, "s").is_ok());
        for bad in [
            "# joints (2): a\n0 0 1\n",
            "# joints (x): a\n",
            "# joints (1): a%zz\n",
        ] {
            let e = parse_skw(bad.as_bytes(), Path::new("t.skw"), 1, 1).unwrap_err();
            assert!(
                matches!(e, ParseError::Malformed { line: 1, .. }),
                "{bad}: {e}"
            );
        }
        let mut sink = Vec::new();
        assert!(write_skw_to(&mut sink, &w, &five, FloatFormat::RoundTrip).is_err());
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

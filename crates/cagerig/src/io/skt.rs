//! Skeleton `.skt`: lines `j <idx> <name> <father> x y z` or
//! `j <idx> <name> <father> rx ry rz x y z` give each joint's GLOBAL rest frame
//! (`Translate · Rz · Ry · Rx`, degrees). `<idx>` is honoured: joint `<idx>` is the joint of
//! that line whatever the order of the lines, and `<father>` refers to these indices (`-1` =
//! root); the indices must be exactly 0 … n−1, each once (a gap or a repeat is an error naming
//! the line). Lines whose first token is not `j` are ignored; a file with no joint line is refused.

use std::io::Write;
use std::path::Path;

use glam::{DMat3, DVec3};

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::euler::{euler_degrees_from_rotation, frame_from_euler_degrees};
use super::text::{FloatFormat, lines};
use crate::skeleton::{Joint, Skeleton};

/// Reads a `.skt` skeleton (joints in file order).
pub fn read_skt(path: &Path) -> Result<Skeleton, ParseError> {
    parse_skt(&read_file(path)?, path)
}

/// Parses `.skt` text; `source` names it in errors.
pub fn parse_skt(data: &[u8], source: &Path) -> Result<Skeleton, ParseError> {
    // (index as written, joint, father as written, line number)
    let mut parsed: Vec<(i64, Joint, i64, usize)> = Vec::new();
    for line in lines(data, source) {
        let line = line?;
        let mut t = line.tokens();
        if t.next_raw() != Some("j") {
            continue;
        }
        let count = line.text.split_whitespace().count();
        if count != 7 && count != 10 {
            return Err(line.malformed(
                "7 tokens (j idx name father x y z) or 10 (j idx name father rx ry rz x y z)",
                format!("{count} tokens"),
            ));
        }
        let idx = t.i64("joint index")?;
        let name = t.text("joint name")?.to_string();
        let father = t.i64("father index")?;
        if father < -1 {
            return Err(line.malformed("father index -1 or a joint index", father.to_string()));
        }
        let degrees = if count == 10 {
            t.vec3("rotation angle (degrees)")?
        } else {
            DVec3::ZERO
        };
        let translation = t.vec3("joint position")?;
        t.end()?;
        parsed.push((
            idx,
            Joint {
                name,
                parent: None,
                rest_world_from_joint: frame_from_euler_degrees(degrees, translation),
            },
            father,
            line.number,
        ));
    }
    let len = parsed.len();
    if len == 0 {
        return Err(ParseError::Rig {
            path: source.to_path_buf(),
            source: crate::error::RigError::Invalid(
                "expected joint lines `j <index> <name> <parent index or -1> x y z`, found no \
                 joint: a skeleton needs at least one"
                    .to_string(),
            ),
        });
    }
    // Line of the joint with each index, to place the joints by their index column.
    let mut line_of_index: Vec<Option<usize>> = vec![None; len];
    for (k, (idx, _, _, number)) in parsed.iter().enumerate() {
        if *idx < 0 || *idx as usize >= len {
            return Err(ParseError::Invalid {
                path: source.to_path_buf(),
                line: *number,
                message: format!(
                    "joint index {idx} is not in 0…{} (the file lists {len} joints, numbered \
                     from 0 in any order)",
                    len.saturating_sub(1)
                ),
            });
        }
        if let Some(first) = line_of_index[*idx as usize].replace(k) {
            return Err(ParseError::Invalid {
                path: source.to_path_buf(),
                line: *number,
                message: format!(
                    "joint index {idx} is used twice (first on line {})",
                    parsed[first].3
                ),
            });
        }
    }
    let mut slots: Vec<Option<Joint>> = vec![None; len];
    for (idx, mut joint, father, number) in parsed {
        let j = idx as usize;
        if father >= 0 {
            if father as usize == j {
                return Err(ParseError::Invalid {
                    path: source.to_path_buf(),
                    line: number,
                    message: format!(
                        "joint {j} ({}) names itself as its father (expected -1 for a root or \
                         another joint's index)",
                        joint.name
                    ),
                });
            }
            if father as usize >= len {
                return Err(ParseError::IndexOutOfRange {
                    path: source.to_path_buf(),
                    line: number,
                    what: "father joint",
                    index: father,
                    len,
                });
            }
            joint.parent = Some(father as usize);
        }
        slots[j] = Some(joint);
    }
    // Every index 0…n−1 was seen exactly once (n lines, no repeat, all in range).
    let joints: Vec<Joint> = slots.into_iter().flatten().collect();
    Skeleton::new(joints).map_err(|e| ParseError::Rig {
        path: source.to_path_buf(),
        source: e,
    })
}

/// Writes a `.skt` (7-token lines; 10-token lines for joints whose rest rotation is not the
/// identity), replacing `path` atomically. Fails if a rest frame is not a rigid transform.
pub fn write_skt(path: &Path, skeleton: &Skeleton) -> Result<(), ParseError> {
    let text = skt_text(skeleton, FloatFormat::RoundTrip).map_err(|message| {
        ParseError::Unrepresentable {
            path: path.to_path_buf(),
            message,
        }
    })?;
    write_atomically(path, |w| w.write_all(text.as_bytes()))
}

/// The `.skt` text of a skeleton, or a message naming the first non-rigid joint frame.
pub fn skt_text(skeleton: &Skeleton, format: FloatFormat) -> Result<String, String> {
    let mut out = String::from("# j <jointIndex> <jointName> <fatherIndex> [rx ry rz] x y z\n");
    for (j, joint) in skeleton.joints().iter().enumerate() {
        let father = joint.parent.map_or(-1, |p| p as i64);
        let frame = joint.rest_world_from_joint;
        if !frame.is_finite() {
            return Err(format!(
                "joint {j} ({}) has a non-finite rest frame (refusing to write it)",
                joint.name
            ));
        }
        let t = frame.translation;
        if frame.matrix3 == DMat3::IDENTITY {
            out += &format!("j {j} {} {father} {}\n", joint.name, format.vectors(&[t]));
        } else {
            let d = euler_degrees_from_rotation(frame.matrix3).ok_or_else(|| {
                format!(
                    "joint {j} ({}) has a rest frame that is not a rotation",
                    joint.name
                )
            })?;
            out += &format!(
                "j {j} {} {father} {}\n",
                joint.name,
                format.vectors(&[d, t])
            );
        }
    }
    Ok(out)
}

/// Writes `.skt` text to any writer.
pub fn write_skt_to(
    w: &mut dyn Write,
    skeleton: &Skeleton,
    format: FloatFormat,
) -> std::io::Result<()> {
    let text = skt_text(skeleton, format).map_err(std::io::Error::other)?;
    w.write_all(text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::RigError;

    fn parse(s: &str) -> Result<Skeleton, ParseError> {
        parse_skt(s.as_bytes(), Path::new("test.skt"))
    }

    #[test]
    fn reads_both_forms_and_ignores_other_lines() {
        let s = parse("# header\n\nj 0 root -1 1 2 3\nx ignored line\nj 1 child 0 0 0 90 4 5 6\n")
            .unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s.parent(1), Some(0));
        assert_eq!(
            s.joint(0).rest_world_from_joint.translation,
            DVec3::new(1.0, 2.0, 3.0)
        );
        let f = s.joint(1).rest_world_from_joint;
        assert_eq!(f.translation, DVec3::new(4.0, 5.0, 6.0));
        assert!(f.transform_vector3(DVec3::X).abs_diff_eq(DVec3::Y, 1e-15));
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("j 0 a -1 0 0 0\nj 1 b 5 0 0 0\n").unwrap_err();
        assert!(
            matches!(
                e,
                ParseError::IndexOutOfRange {
                    line: 2,
                    index: 5,
                    ..
                }
            ),
            "{e}"
        );
        let e = parse("j 0 a -1 0 0\n").unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 1, .. }));
        let e = parse("\nj 0 a -1 0 y 0\n").unwrap_err();
        assert!(matches!(&e, ParseError::Malformed { line: 2, found, .. } if found == "y"));
        let e = parse("j 0 a -2 0 0 0\n").unwrap_err();
        assert_eq!(e.line(), Some(1));
        let e = parse("j 0 a -1 0 0 0\nj 1 a 0 0 0 0\n").unwrap_err();
        assert!(matches!(
            e,
            ParseError::Rig {
                source: RigError::DuplicateJointName { .. },
                ..
            }
        ));
        let e = parse("j 0 a 1 0 0 0\nj 1 b 0 0 0 0\n").unwrap_err();
        assert!(matches!(
            e,
            ParseError::Rig {
                source: RigError::Cycle { .. },
                ..
            }
        ));
    }

    #[test]
    fn a_file_with_no_joint_is_refused_naming_the_file() {
        for text in ["", "# only a comment\n\n", "x not a joint line\n"] {
            let e = parse(text).unwrap_err();
            let message = e.to_string();
            assert!(
                message.starts_with("test.skt: ") && message.contains("found no joint"),
                "{message}"
            );
        }
    }

    #[test]
    fn index_column_is_honoured_and_checked() {
        // Swapped lines: the same rig as in order.
        let ordered = parse("j 0 root -1 0 0 0\nj 1 mid 0 1 0 0\nj 2 tip 1 2 0 0\n").unwrap();
        let swapped = parse("j 0 root -1 0 0 0\nj 2 tip 1 2 0 0\nj 1 mid 0 1 0 0\n").unwrap();
        assert_eq!(ordered, swapped);
        assert_eq!(swapped.joint(2).name, "tip");
        assert_eq!(swapped.parent(2), Some(1));
        let e = parse("j 0 a -1 0 0 0\nj 0 b 0 0 0 0\n").unwrap_err();
        assert!(
            matches!(&e, ParseError::Invalid { line: 2, message, .. } if message.contains("twice")),
            "{e}"
        );
        let e = parse("j 0 a -1 0 0 0\nj 5 b 0 0 0 0\n").unwrap_err();
        assert!(matches!(&e, ParseError::Invalid { line: 2, .. }), "{e}");
        let e = parse("j 0 a -1 0 0 0\nj 1 b 1 0 0 0\n").unwrap_err();
        assert!(
            matches!(&e, ParseError::Invalid { line: 2, message, .. } if message.contains("itself")),
            "{e}"
        );
        // A joint at 1e308: rejected with the line and the value.
        let e = parse("j 0 a -1 1e308 0 0\n").unwrap_err();
        assert!(
            matches!(&e, ParseError::Malformed { line: 1, found, .. } if found == "1e308"),
            "{e}"
        );
    }

    #[test]
    fn write_read_round_trip() {
        let s = parse("j 0 root -1 1 2 3\nj 1 child 0 10 -20 30 4 5 6\nj 2 tip 1 0.1 0.2 0.3\n")
            .unwrap();
        let text = skt_text(&s, FloatFormat::RoundTrip).unwrap();
        assert_eq!(
            text.lines()
                .filter(|l| l.split_whitespace().count() == 10)
                .count(),
            1
        );
        let back = parse(&text).unwrap();
        for (a, b) in back.joints().iter().zip(s.joints()) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.parent, b.parent);
            assert!(
                a.rest_world_from_joint
                    .abs_diff_eq(b.rest_world_from_joint, 1e-12)
            );
        }
        assert_eq!(back.joint(2), s.joint(2));
    }
}

//! Skeleton animation (`arm_skelAnim.txt`, `.ska`): `k <time>` lines first, then
//! `s <keyframeIndex> …` lines, one per joint in joint order (index implicit).
//!
//! Version, from the header lines before the first `k` (whole trimmed line, exact match):
//! `#V2`, `# V2` or `t rt` → V2; `#V3` or `# V3` → V3; otherwise V1.
//! - V1: 16 numbers, the 4×4 LOCAL transform `parent_from_joint`, column-major.
//! - V2: `rx ry rz tx ty tz` (Euler degrees, `T = Translate·Rz·Ry·Rx`) = a delta K_j w.r.t. the
//!   rest local L_rest_j: roots first get `K.t −= L_rest.t`, then `L_j = L_rest_j · K_j`.
//! - V3: `rx ry rz tx ty tz` = the GLOBAL current frame G_j; `L_j = G_parent⁻¹ · G_j`, roots keep
//!   G_j.
//!
//! Keyframes are returned as local transforms in a [`SkeletonTrack`].
//!
//! Note: the tool's `cg3::Transform::cumulateWith(t)` is `this · t`, so its code actually
//! computes `G_j · G_parent⁻¹` (V3) and `K_j · L_rest_j` (V2, with rest locals
//! `G_rest_j · G_rest_parent⁻¹`); these agree with the formulas above only when the rotations
//! involved commute. On the Arm V3 file they do not (local rotation entries differ by up to
//! 0.76). [`LocalComposition::Correct`] (the default, [`parse_skeleton_animation`]) makes forward
//! kinematics reproduce the V3 global frames exactly; [`LocalComposition::PaperTool`]
//! reproduces the tool's locals, for conformance comparisons against its outputs.

use std::io::Write;
use std::path::Path;

use glam::{DAffine3, DVec3};

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::euler::{euler_degrees_from_rotation, frame_from_euler_degrees};
use super::keyframes::parse_keyframed;
use super::text::FloatFormat;
use crate::animation::SkeletonTrack;
use crate::skeleton::Skeleton;

/// Tolerance on the bottom row `(0 0 0 1)` of a V1 matrix.
pub const AFFINE_ROW_TOLERANCE: f64 = 1e-9;

/// The three on-disk variants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkeletonAnimationVersion {
    /// 4×4 local matrices, column-major.
    V1LocalMatrices,
    /// Euler + translation deltas w.r.t. the rest locals.
    V2RestDeltas,
    /// Euler + translation of the global current frames.
    V3GlobalFrames,
}

/// How keyframe values are turned into local transforms (see the module notes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LocalComposition {
    /// V3: `L_j = G_parent⁻¹ · G_j`; V2: `L_j = L_rest_j · K_j`.
    #[default]
    Correct,
    /// What the tool's code computes: V3 `G_j · G_parent⁻¹`; V2 `K_j · L_rest_j` with
    /// `L_rest_j = G_rest_j · G_rest_parent⁻¹`.
    PaperTool,
}

/// Detects the version from one header line (`None` if the line is not a version marker).
pub fn version_marker(line: &str) -> Option<SkeletonAnimationVersion> {
    match line.trim() {
        "#V2" | "# V2" | "t rt" => Some(SkeletonAnimationVersion::V2RestDeltas),
        "#V3" | "# V3" => Some(SkeletonAnimationVersion::V3GlobalFrames),
        _ => None,
    }
}

/// Reads a skeleton animation for `skeleton`; keys are local `parent_from_joint` transforms.
pub fn read_skeleton_animation(
    path: &Path,
    skeleton: &Skeleton,
) -> Result<(SkeletonTrack, SkeletonAnimationVersion), ParseError> {
    parse_skeleton_animation(&read_file(path)?, path, skeleton)
}

/// Reads a skeleton animation with the given local-transform convention.
pub fn read_skeleton_animation_with(
    path: &Path,
    skeleton: &Skeleton,
    composition: LocalComposition,
) -> Result<(SkeletonTrack, SkeletonAnimationVersion), ParseError> {
    parse_skeleton_animation_with(&read_file(path)?, path, skeleton, composition)
}

/// Parses skeleton-animation text ([`LocalComposition::Correct`]).
pub fn parse_skeleton_animation(
    data: &[u8],
    source: &Path,
    skeleton: &Skeleton,
) -> Result<(SkeletonTrack, SkeletonAnimationVersion), ParseError> {
    parse_skeleton_animation_with(data, source, skeleton, LocalComposition::Correct)
}

/// Parses skeleton-animation text with the given local-transform convention.
pub fn parse_skeleton_animation_with(
    data: &[u8],
    source: &Path,
    skeleton: &Skeleton,
    composition: LocalComposition,
) -> Result<(SkeletonTrack, SkeletonAnimationVersion), ParseError> {
    let tool = composition == LocalComposition::PaperTool;
    let mut version = SkeletonAnimationVersion::V1LocalMatrices;
    // Peek the header first: the number of values per record depends on it.
    let mut probe_version = None;
    for line in super::text::lines(data, source) {
        let Ok(line) = line else { break };
        if line.text.split_whitespace().next() == Some("k") {
            break;
        }
        if let Some(v) = version_marker(line.text) {
            probe_version.get_or_insert(v);
        }
    }
    if let Some(v) = probe_version {
        version = v;
    }
    let values = match version {
        SkeletonAnimationVersion::V1LocalMatrices => 16,
        _ => 6,
    };
    let num_joints = skeleton.len();
    let parsed = parse_keyframed(data, source, "s", values, num_joints, "joints", |_| {})?;

    let rest_world = skeleton.rest_world_from_joint();
    let mut rest_local = vec![DAffine3::IDENTITY; num_joints];
    skeleton.locals_from_worlds(&rest_world, &mut rest_local);
    if tool {
        for (j, l) in rest_local.iter_mut().enumerate() {
            if let Some(p) = skeleton.parent(j) {
                *l = rest_world[j] * rest_world[p].inverse();
            }
        }
    }

    let mut keys = Vec::with_capacity(parsed.records.len());
    for (k, key) in parsed.records.iter().enumerate() {
        let mut locals = vec![DAffine3::IDENTITY; num_joints];
        match version {
            SkeletonAnimationVersion::V1LocalMatrices => {
                for (j, m) in key.iter().enumerate() {
                    if m[3].abs() > AFFINE_ROW_TOLERANCE
                        || m[7].abs() > AFFINE_ROW_TOLERANCE
                        || m[11].abs() > AFFINE_ROW_TOLERANCE
                        || (m[15] - 1.0).abs() > AFFINE_ROW_TOLERANCE
                    {
                        return Err(ParseError::Invalid {
                            path: source.to_path_buf(),
                            line: parsed.record_lines[k][j],
                            message: "the 4×4 matrix is not affine: its bottom row must be 0 0 0 1"
                                .into(),
                        });
                    }
                    locals[j] = DAffine3::from_cols(
                        DVec3::new(m[0], m[1], m[2]),
                        DVec3::new(m[4], m[5], m[6]),
                        DVec3::new(m[8], m[9], m[10]),
                        DVec3::new(m[12], m[13], m[14]),
                    );
                }
            }
            SkeletonAnimationVersion::V2RestDeltas => {
                for (j, v) in key.iter().enumerate() {
                    let mut delta = frame_from_euler_degrees(
                        DVec3::new(v[0], v[1], v[2]),
                        DVec3::new(v[3], v[4], v[5]),
                    );
                    if skeleton.parent(j).is_none() {
                        delta.translation -= rest_local[j].translation;
                    }
                    locals[j] = if tool {
                        delta * rest_local[j]
                    } else {
                        rest_local[j] * delta
                    };
                }
            }
            SkeletonAnimationVersion::V3GlobalFrames => {
                let globals: Vec<DAffine3> = key
                    .iter()
                    .map(|v| {
                        frame_from_euler_degrees(
                            DVec3::new(v[0], v[1], v[2]),
                            DVec3::new(v[3], v[4], v[5]),
                        )
                    })
                    .collect();
                skeleton.locals_from_worlds(&globals, &mut locals);
                if tool {
                    for (j, l) in locals.iter_mut().enumerate() {
                        if let Some(p) = skeleton.parent(j) {
                            *l = globals[j] * globals[p].inverse();
                        }
                    }
                }
            }
        }
        keys.push(locals);
    }
    let track = SkeletonTrack::new(parsed.times, keys).map_err(|e| ParseError::Animation {
        path: source.to_path_buf(),
        source: e,
    })?;
    Ok((track, version))
}

/// Writes a skeleton animation as V3 (global frames from forward kinematics, Euler degrees) or
/// V1 (local 4×4 matrices, column-major), replacing `path` atomically. V3 fails if a global
/// frame is not rigid.
pub fn write_skeleton_animation(
    path: &Path,
    track: &SkeletonTrack,
    skeleton: &Skeleton,
    version: SkeletonAnimationVersion,
    format: FloatFormat,
) -> Result<(), ParseError> {
    let text = skeleton_animation_text(track, skeleton, version, format).map_err(|message| {
        ParseError::Unrepresentable {
            path: path.to_path_buf(),
            message,
        }
    })?;
    write_atomically(path, |w| w.write_all(text.as_bytes()))
}

/// The text of a skeleton animation (see [`write_skeleton_animation`]). V2 is written as V3.
pub fn skeleton_animation_text(
    track: &SkeletonTrack,
    skeleton: &Skeleton,
    version: SkeletonAnimationVersion,
    format: FloatFormat,
) -> Result<String, String> {
    if track.num_joints() != skeleton.len() {
        return Err(format!(
            "the track has {} joints but the skeleton has {}",
            track.num_joints(),
            skeleton.len()
        ));
    }
    for (k, locals) in track.keys().iter().enumerate() {
        if let Some(j) = locals.iter().position(|l| !l.is_finite()) {
            return Err(format!(
                "keyframe {k}: joint {j} has a non-finite transform (refusing to write it)"
            ));
        }
    }
    if let Some(t) = track.times().iter().find(|t| !t.is_finite()) {
        return Err(format!(
            "keyframe time {t} is not finite (refusing to write it)"
        ));
    }
    let f = |x: f64| format.format(x);
    let mut out = String::new();
    let v1 = version == SkeletonAnimationVersion::V1LocalMatrices;
    if !v1 {
        out += "# V3\n# s <keyframeIndex> <global rotation rx ry rz (degrees)> <global translation x y z>\n";
    }
    for t in track.times() {
        out += &format!("k {}\n", f(*t));
    }
    let mut world = vec![DAffine3::IDENTITY; skeleton.len()];
    for (k, locals) in track.keys().iter().enumerate() {
        if v1 {
            for l in locals {
                let m = l.matrix3;
                let t = l.translation;
                let cols = [
                    m.x_axis.x, m.x_axis.y, m.x_axis.z, 0.0, m.y_axis.x, m.y_axis.y, m.y_axis.z,
                    0.0, m.z_axis.x, m.z_axis.y, m.z_axis.z, 0.0, t.x, t.y, t.z, 1.0,
                ];
                out += &format!("s {k}");
                for c in cols {
                    out += " ";
                    out += &f(c);
                }
                out += "\n";
            }
        } else {
            skeleton.forward_kinematics(locals, &mut world);
            for (j, g) in world.iter().enumerate() {
                let d = euler_degrees_from_rotation(g.matrix3).ok_or_else(|| {
                    format!("keyframe {k}: the global frame of joint {j} is not rigid")
                })?;
                out += &format!("s {k} {}\n", format.vectors(&[d, g.translation]));
            }
        }
    }
    Ok(out)
}

/// Writes skeleton-animation text to any writer.
pub fn write_skeleton_animation_to(
    w: &mut dyn Write,
    track: &SkeletonTrack,
    skeleton: &Skeleton,
    version: SkeletonAnimationVersion,
    format: FloatFormat,
) -> std::io::Result<()> {
    let text =
        skeleton_animation_text(track, skeleton, version, format).map_err(std::io::Error::other)?;
    w.write_all(text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Joint;

    /// root at (1,0,0), child at (1,2,0): rest locals root = T(1,0,0), child = T(0,2,0).
    fn skeleton() -> Skeleton {
        Skeleton::new(vec![
            Joint {
                name: "root".into(),
                parent: None,
                rest_world_from_joint: DAffine3::from_translation(DVec3::X),
            },
            Joint {
                name: "child".into(),
                parent: Some(0),
                rest_world_from_joint: DAffine3::from_translation(DVec3::new(1.0, 2.0, 0.0)),
            },
        ])
        .unwrap()
    }

    fn parse(s: &str) -> Result<(SkeletonTrack, SkeletonAnimationVersion), ParseError> {
        parse_skeleton_animation(s.as_bytes(), Path::new("a.txt"), &skeleton())
    }

    #[test]
    fn detects_versions() {
        assert_eq!(
            version_marker("# V3 "),
            Some(SkeletonAnimationVersion::V3GlobalFrames)
        );
        assert_eq!(
            version_marker("t rt"),
            Some(SkeletonAnimationVersion::V2RestDeltas)
        );
        assert_eq!(
            version_marker("#V2"),
            Some(SkeletonAnimationVersion::V2RestDeltas)
        );
        assert_eq!(version_marker("# V4"), None);
    }

    #[test]
    fn v3_globals_become_locals_that_fk_reproduces() {
        // Keyframe 0: rest. Keyframe 1: root rotated 90° about z at (1,0,0); child global
        // = root global · T(0,2,0) = at (1,0,0) + Rz90·(0,2,0) = (-1,0,0), also rotated 90°.
        let (track, version) = parse(
            "# V3\nk 0\nk 2\ns 0 0 0 0 1 0 0\ns 0 0 0 0 1 2 0\ns 1 0 0 90 1 0 0\ns 1 0 0 90 -1 0 0\n",
        )
        .unwrap();
        assert_eq!(version, SkeletonAnimationVersion::V3GlobalFrames);
        let s = skeleton();
        assert_eq!(
            track.keys()[0][1],
            DAffine3::from_translation(DVec3::new(0.0, 2.0, 0.0))
        );
        let child_local = track.keys()[1][1];
        assert!(
            child_local.abs_diff_eq(DAffine3::from_translation(DVec3::new(0.0, 2.0, 0.0)), 1e-12)
        );
        let mut world = vec![DAffine3::IDENTITY; 2];
        s.forward_kinematics(&track.keys()[1], &mut world);
        assert!(
            world[1]
                .translation
                .abs_diff_eq(DVec3::new(-1.0, 0.0, 0.0), 1e-12)
        );
        // Write V3 and read back.
        let text = skeleton_animation_text(&track, &s, version, FloatFormat::RoundTrip).unwrap();
        let (back, v) = parse(&text).unwrap();
        assert_eq!(v, SkeletonAnimationVersion::V3GlobalFrames);
        for (a, b) in back
            .keys()
            .iter()
            .flatten()
            .zip(track.keys().iter().flatten())
        {
            assert!(a.abs_diff_eq(*b, 1e-12));
        }
    }

    #[test]
    fn paper_tool_composition_reverses_the_products() {
        // Root rotated 90° about z, child rotated 90° about x (globals): the orders differ.
        let text = "# V3\nk 0\ns 0 0 0 90 1 0 0\ns 0 90 0 0 1 2 0\n";
        let s = skeleton();
        let (ours, _) = parse(text).unwrap();
        let (tool, _) = parse_skeleton_animation_with(
            text.as_bytes(),
            Path::new("a.txt"),
            &s,
            LocalComposition::PaperTool,
        )
        .unwrap();
        let g_root = frame_from_euler_degrees(DVec3::new(0.0, 0.0, 90.0), DVec3::X);
        let g_child =
            frame_from_euler_degrees(DVec3::new(90.0, 0.0, 0.0), DVec3::new(1.0, 2.0, 0.0));
        assert!(ours.keys()[0][1].abs_diff_eq(g_root.inverse() * g_child, 1e-12));
        assert!(tool.keys()[0][1].abs_diff_eq(g_child * g_root.inverse(), 1e-12));
        assert!(!ours.keys()[0][1].abs_diff_eq(tool.keys()[0][1], 1e-3));
        assert_eq!(ours.keys()[0][0], tool.keys()[0][0]);
    }

    #[test]
    fn v2_deltas_compose_with_rest_locals() {
        // Root: delta translation (1,0,0) written as absolute "rest local + delta"? The root's
        // translation has its rest local translation subtracted: t = (3,0,0) - (1,0,0) = (2,0,0),
        // then L = T(1,0,0)·T(2,0,0) = T(3,0,0). Child: L = T(0,2,0)·Rz(90).
        let (track, version) = parse("#V2\nk 0\ns 0 0 0 0 3 0 0\ns 0 0 0 90 0 0 0\n").unwrap();
        assert_eq!(version, SkeletonAnimationVersion::V2RestDeltas);
        assert!(
            track.keys()[0][0]
                .abs_diff_eq(DAffine3::from_translation(DVec3::new(3.0, 0.0, 0.0)), 1e-15)
        );
        let expect = DAffine3::from_translation(DVec3::new(0.0, 2.0, 0.0))
            * DAffine3::from_rotation_z(std::f64::consts::FRAC_PI_2);
        assert!(track.keys()[0][1].abs_diff_eq(expect, 1e-15));
    }

    #[test]
    fn v1_reads_column_major_local_matrices_and_round_trips() {
        let text =
            "k 0\ns 0 1 0 0 0 0 1 0 0 0 0 1 0 5 6 7 1\ns 0 0 1 0 0 -1 0 0 0 0 0 1 0 1 2 3 1\n";
        let (track, version) = parse(text).unwrap();
        assert_eq!(version, SkeletonAnimationVersion::V1LocalMatrices);
        assert_eq!(
            track.keys()[0][0],
            DAffine3::from_translation(DVec3::new(5.0, 6.0, 7.0))
        );
        let l = track.keys()[0][1];
        assert_eq!(l.transform_vector3(DVec3::X), DVec3::Y);
        assert_eq!(l.translation, DVec3::new(1.0, 2.0, 3.0));
        let out =
            skeleton_animation_text(&track, &skeleton(), version, FloatFormat::RoundTrip).unwrap();
        assert_eq!(parse(&out).unwrap().0, track);
        let e = parse(
            "k 0\ns 0 1 0 0 0 0 1 0 0 0 0 1 0 5 6 7 2\ns 0 1 0 0 0 0 1 0 0 0 0 1 0 5 6 7 1\n",
        )
        .unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 2, .. }), "{e}");
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("# V3\nk 0\ns 0 0 0 0 1 0 0\nk 1\n").unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 4, .. }), "{e}");
        let e = parse("# V3\nk 0\ns 0 0 0 0 1 0 0\n").unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 2, .. }), "{e}");
        let e =
            parse("# V3\nk 0\ns 0 0 0 0 1 0 0\ns 0 0 0 0 1 0 0\ns 0 0 0 0 1 0 0\n").unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 5, .. }), "{e}");
        let e = parse("# V3\nk 0\ns 0 0 0 0 1 0\n").unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 3, .. }), "{e}");
        let e = parse("# V3\nk 0\nk -1\n").unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 3, .. }), "{e}");
    }
}

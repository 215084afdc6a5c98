//! Cage animation (`arm_cageAnim.txt`): `k <time>` lines first, then `c <keyframeIndex> dx dy dz`,
//! one per cage vertex in vertex order. The values are offsets of the REST cage C from the
//! original rest cage (C = C_original + offset).

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use super::atomic::{read_file, write_atomically};
use super::error::ParseError;
use super::keyframes::parse_keyframed;
use super::text::FloatFormat;
use crate::animation::CageTrack;

/// Reads a cage animation for a cage of `num_cage_vertices` vertices.
pub fn read_cage_animation(path: &Path, num_cage_vertices: usize) -> Result<CageTrack, ParseError> {
    parse_cage_animation(&read_file(path)?, path, num_cage_vertices)
}

/// Parses cage-animation text.
pub fn parse_cage_animation(
    data: &[u8],
    source: &Path,
    num_cage_vertices: usize,
) -> Result<CageTrack, ParseError> {
    let parsed = parse_keyframed(
        data,
        source,
        "c",
        3,
        num_cage_vertices,
        "cage vertices",
        |_| {},
    )?;
    let offsets = parsed
        .records
        .iter()
        .map(|key| key.iter().map(|v| DVec3::new(v[0], v[1], v[2])).collect())
        .collect();
    CageTrack::new(parsed.times, offsets).map_err(|e| ParseError::Animation {
        path: source.to_path_buf(),
        source: e,
    })
}

/// Writes a cage animation, replacing `path` atomically.
pub fn write_cage_animation(
    path: &Path,
    track: &CageTrack,
    format: FloatFormat,
) -> Result<(), ParseError> {
    write_atomically(path, |w| write_cage_animation_to(w, track, format))
}

/// Writes cage-animation text to any writer.
pub fn write_cage_animation_to(
    w: &mut dyn Write,
    track: &CageTrack,
    format: FloatFormat,
) -> std::io::Result<()> {
    for t in track.times() {
        writeln!(w, "k {}", format.checked(*t)?)?;
    }
    for (k, key) in track.offsets().iter().enumerate() {
        for d in key {
            writeln!(
                w,
                "c {k} {} {} {}",
                format.checked(d.x)?,
                format.checked(d.y)?,
                format.checked(d.z)?
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_and_round_trips() {
        let p = Path::new("c.txt");
        let text = b"k 0\nk 1.5\nc 0 0 0 0\nc 1 1 2 3\nc 0 0 0 1\nc 1 4 5 6\n";
        let track = parse_cage_animation(text, p, 2).unwrap();
        assert_eq!(track.times(), &[0.0, 1.5]);
        assert_eq!(track.offsets()[0], vec![DVec3::ZERO, DVec3::Z]);
        assert_eq!(track.offsets()[1][1], DVec3::new(4.0, 5.0, 6.0));
        let mut out = Vec::new();
        write_cage_animation_to(&mut out, &track, FloatFormat::RoundTrip).unwrap();
        assert_eq!(parse_cage_animation(&out, p, 2).unwrap(), track);
    }

    #[test]
    fn errors_name_the_line() {
        let p = Path::new("c.txt");
        let e = parse_cage_animation(b"k 0\nc 0 1 1 1\nk 1\n", p, 1).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 3, .. }), "{e}");
        let e = parse_cage_animation(b"k 0\nc 1 1 1 1\n", p, 1).unwrap_err();
        assert!(matches!(
            e,
            ParseError::IndexOutOfRange {
                line: 2,
                what: "keyframe",
                ..
            }
        ));
        let e = parse_cage_animation(b"k 0\nc 0 1 1 1\nc 0 1 1 1\n", p, 1).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 3, .. }));
        let e =
            parse_cage_animation(b"k 0\nk 1\nc 0 1 1 1\nc 0 1 1 1\nc 1 1 1 1\n", p, 2).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 2, .. }), "{e}");
        let e = parse_cage_animation(b"k 1\nk 1\n", p, 0).unwrap_err();
        assert!(matches!(e, ParseError::Invalid { line: 2, .. }));
        let e = parse_cage_animation(b"k 0\nc 0 1 1\n", p, 1).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 2, .. }));
        let e = parse_cage_animation(b"# nothing\n", p, 1).unwrap_err();
        assert!(matches!(e, ParseError::Malformed { line: 1, .. }));
    }
}

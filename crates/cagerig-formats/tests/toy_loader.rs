//! A character loader from outside the library, written as `docs/architecture.md` ("A character
//! format") says for a loader of another crate: it reads its own file into an
//! `ImportedCharacter`, and `open_imported_character` applies the rule every front end follows
//! (the cage given, found or generated; the rig's parts assembled). The toy format is a text
//! file of `v x y z`, `f a b c` (0-based), `j name parent x y z` (parent −1 for the root, joints
//! in parent-first order, rest frames translations) and `w vertex joint weight` lines. The test
//! opens a toy bar with a generated cage, binds it and bends it.

use std::path::Path;

use cagerig::cage_gen::CageOptions;
use cagerig::cage_source::{CageOrigin, CageRequest};
use cagerig::mesh::TriMesh;
use cagerig::session::{RigSession, SessionOptions};
use cagerig::skeleton::{Joint, Skeleton};
use cagerig::skin_weights::SkinWeights;
use cagerig_formats::ImportedCharacter;
use cagerig_formats::open_character::open_imported_character;
use glam::{DAffine3, DVec3};

/// Why a toy file could not be read: the line and what was wrong with it.
#[derive(Debug)]
struct ToyError {
    line: usize,
    message: String,
}

/// The toy loader: the whole file into an `ImportedCharacter`.
fn read_toy(text: &str) -> Result<ImportedCharacter, ToyError> {
    let (mut positions, mut triangles, mut joints, mut triplets) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (index, line) in text.lines().enumerate() {
        let error = |message: String| ToyError {
            line: index + 1,
            message,
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        let number = |k: usize| -> Result<f64, ToyError> {
            fields
                .get(k)
                .and_then(|f| f.parse::<f64>().ok())
                .filter(|x| x.is_finite())
                .ok_or_else(|| error(format!("field {k} is not a finite number")))
        };
        let index_at = |k: usize| -> Result<usize, ToyError> {
            fields
                .get(k)
                .and_then(|f| f.parse::<usize>().ok())
                .ok_or_else(|| error(format!("field {k} is not an index")))
        };
        match fields.first().copied() {
            Some("v") => positions.push(DVec3::new(number(1)?, number(2)?, number(3)?)),
            Some("f") => triangles.push([
                u32::try_from(index_at(1)?).map_err(|e| error(e.to_string()))?,
                u32::try_from(index_at(2)?).map_err(|e| error(e.to_string()))?,
                u32::try_from(index_at(3)?).map_err(|e| error(e.to_string()))?,
            ]),
            Some("j") => joints.push(Joint {
                name: fields.get(1).map(|s| s.to_string()).unwrap_or_default(),
                parent: match fields.get(2).copied() {
                    Some("-1") => None,
                    _ => Some(index_at(2)?),
                },
                rest_world_from_joint: DAffine3::from_translation(DVec3::new(
                    number(3)?,
                    number(4)?,
                    number(5)?,
                )),
            }),
            Some("w") => triplets.push((index_at(1)?, index_at(2)?, number(3)?)),
            None | Some("#") => {}
            Some(other) => return Err(error(format!("unknown line kind {other:?}"))),
        }
    }
    let at_end = |message: String| ToyError {
        line: text.lines().count(),
        message,
    };
    let mesh = TriMesh::new(positions, triangles).map_err(|e| at_end(e.to_string()))?;
    let skeleton = Skeleton::new(joints).map_err(|e| at_end(e.to_string()))?;
    let (skin_weights, _renormalised) =
        SkinWeights::from_triplets(mesh.num_vertices(), skeleton.len(), triplets)
            .map_err(|e| at_end(e.to_string()))?;
    Ok(ImportedCharacter {
        node_pose: skeleton
            .joints()
            .iter()
            .map(|j| match j.parent {
                Some(p) => {
                    skeleton.joints()[p].rest_world_from_joint.inverse() * j.rest_world_from_joint
                }
                None => j.rest_world_from_joint,
            })
            .collect(),
        mesh,
        skeleton,
        skin_weights,
        cage: None,
        animations: Vec::new(),
        morph_targets: Default::default(),
        summary: Default::default(),
        skinning: None,
        dq_blend_weights: None,
        warnings: Vec::new(),
    })
}

/// A square tube along +X, `rings` rings of 8 vertices from x = 0 to 2, capped, with three
/// joints at x = 0, 1 and 2 and weights falling off linearly between them, as toy text.
fn toy_bar(rings: usize) -> String {
    let mut text = String::from("# a toy bar\n");
    let sides = 8;
    for r in 0..rings {
        let x = 2.0 * r as f64 / (rings - 1) as f64;
        for k in 0..sides {
            let a = std::f64::consts::TAU * k as f64 / sides as f64;
            text += &format!("v {x} {} {}\n", 0.2 * a.cos(), 0.2 * a.sin());
        }
    }
    let at = |r: usize, k: usize| r * sides + k % sides;
    for r in 0..rings - 1 {
        for k in 0..sides {
            let (a, b, c, d) = (at(r, k), at(r, k + 1), at(r + 1, k), at(r + 1, k + 1));
            text += &format!("f {a} {c} {b}\nf {b} {c} {d}\n");
        }
    }
    for k in 1..sides - 1 {
        text += &format!("f 0 {} {}\n", k, k + 1);
        let last = (rings - 1) * sides;
        text += &format!("f {last} {} {}\n", last + k + 1, last + k);
    }
    text += "j root -1 0 0 0\nj elbow 0 1 0 0\nj tip 1 2 0 0\n";
    for r in 0..rings {
        let x = 2.0 * r as f64 / (rings - 1) as f64;
        let to_elbow = (1.0 - (x - 1.0).abs()).max(0.0);
        for k in 0..sides {
            let v = at(r, k);
            if x <= 1.0 {
                text += &format!("w {v} 0 {}\nw {v} 1 {to_elbow}\n", 1.0 - to_elbow);
            } else {
                text += &format!("w {v} 1 {to_elbow}\nw {v} 2 {}\n", 1.0 - to_elbow);
            }
        }
    }
    text
}

#[test]
fn a_loader_of_another_crate_opens_binds_and_bends_its_character() {
    let imported = read_toy(&toy_bar(21)).unwrap();
    assert_eq!(imported.mesh.num_vertices(), 168);
    let opened = open_imported_character(
        Path::new("bar.toy"),
        imported,
        &CageRequest {
            given: None,
            generate: Some(CageOptions::default()),
            generated: None,
        },
    )
    .unwrap();
    assert!(matches!(opened.cage_origin, CageOrigin::Generated(_)));
    let (mut session, _) = RigSession::new(opened.parts, SessionOptions::default()).unwrap();
    let tip_at_rest = session.posed_mesh()[167];
    session
        .rotate_joint(1, DVec3::Z, std::f64::consts::FRAC_PI_4)
        .unwrap();
    let tip = session.posed_mesh()[167];
    assert!(
        tip.y > tip_at_rest.y + 0.4,
        "the elbow bends the tip up: {tip_at_rest} → {tip}"
    );
    // The coupling works on it: a current-cage grab lands exactly.
    let target = session.posed_cage()[0] + DVec3::new(0.0, 0.01, 0.0);
    session
        .move_posed_cage(&[0], &[DVec3::new(0.0, 0.01, 0.0)])
        .unwrap();
    assert!(session.posed_cage()[0].distance(target) < 1e-9);
}

#[test]
fn the_toy_loader_names_the_line_it_cannot_read() {
    let error = read_toy("v 0 0 0\nv 1 x 0\n").unwrap_err();
    assert_eq!(error.line, 2);
    assert!(error.message.contains("field 2"), "{}", error.message);
}

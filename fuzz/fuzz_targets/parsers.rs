//! Every text reader on arbitrary bytes: the first byte picks the reader, the rest is the file.
//! Beyond "no panic": whatever a reader accepts holds only finite numbers within the input
//! bound, an accepted OBJ survives a write/read round trip bit for bit, and accepted DQ blend
//! weights lie in [0, 1] and survive a write/read round trip.
#![no_main]

use std::path::Path;

use cagerig::error::is_input_value;
use cagerig::io;
use cagerig::{Joint, Skeleton};
use glam::{DAffine3, DVec3};
use libfuzzer_sys::fuzz_target;

fn skeleton() -> Skeleton {
    Skeleton::new(vec![
        Joint {
            name: "a".into(),
            parent: None,
            rest_world_from_joint: DAffine3::IDENTITY,
        },
        Joint {
            name: "b".into(),
            parent: Some(0),
            rest_world_from_joint: DAffine3::from_translation(DVec3::X),
        },
    ])
    .unwrap()
}

fn finite(p: DVec3) -> bool {
    p.to_array().iter().all(|&x| is_input_value(x))
}

fuzz_target!(|input: &[u8]| {
    let Some((&which, data)) = input.split_first() else {
        return;
    };
    let src = Path::new("fuzz");
    match which % 9 {
        0 => {
            if let Ok(m) = io::parse_obj(data, src) {
                assert!(m.positions.iter().all(|p| finite(*p)));
                let mut bytes = Vec::new();
                io::obj::write_obj_to(&mut bytes, &m.positions, &m.triangles, io::FloatFormat::RoundTrip)
                    .unwrap();
                let back = io::parse_obj(&bytes, src).unwrap();
                assert_eq!(back, m);
            }
        }
        1 => {
            if let Ok(s) = io::parse_skt(data, src) {
                assert!(s.joints().iter().all(|j| finite(j.rest_world_from_joint.translation)));
            }
        }
        2 => {
            if let Ok((w, _)) = io::parse_skw(data, src, 3, 2) {
                for v in 0..3 {
                    assert!(w.row(v).1.iter().all(|x| x.is_finite()));
                }
            }
        }
        3 => {
            if let Ok(phi) = io::parse_cage_weights(data, src, 3, 4) {
                for i in 0..3 {
                    for k in 0..4 {
                        assert!(is_input_value(phi.get(i, k)));
                    }
                }
            }
        }
        4 => {
            let _ = io::parse_cor_weights(data, src, 3);
        }
        5 => {
            let _ = io::parse_maxvol(data, src, 3);
        }
        6 => {
            let _ = io::parse_skeleton_animation(data, src, &skeleton());
        }
        7 => {
            if let Ok(b) = io::parse_dq_blend_weights(data, src, 3) {
                assert!(b.values().iter().all(|x| (0.0..=1.0).contains(x)));
                let mut bytes = Vec::new();
                io::dq_blend_weights::write_dq_blend_weights_to(&mut bytes, &b, io::FloatFormat::RoundTrip)
                    .unwrap();
                assert_eq!(io::parse_dq_blend_weights(&bytes, src, 3).unwrap(), b);
            }
        }
        _ => {
            let _ = io::parse_cage_animation(data, src, 2);
        }
    }
});

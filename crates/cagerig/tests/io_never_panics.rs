//! Property tests: no reader panics, whatever the bytes.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;

use cagerig::io;
use cagerig::{Joint, Skeleton};
use glam::{DAffine3, DVec3};
use proptest::prelude::*;

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

fn run_all(data: &[u8]) {
    let src = Path::new("fuzz");
    let _ = io::parse_obj(data, src);
    let _ = io::parse_skt(data, src);
    let _ = io::parse_skw(data, src, 3, 2);
    let _ = io::parse_cage_weights(data, src, 3, 4);
    let _ = io::parse_cor_weights(data, src, 3);
    let _ = io::parse_maxvol(data, src, 3);
    let _ = io::parse_skeleton_animation(data, src, &skeleton());
    let _ = io::parse_cage_animation(data, src, 2);
}

/// Lines of plausible tokens, so the parsers get past the first token.
fn token_soup() -> impl Strategy<Value = Vec<u8>> {
    let token = prop_oneof![
        Just("v".to_string()),
        Just("f".to_string()),
        Just("j".to_string()),
        Just("k".to_string()),
        Just("s".to_string()),
        Just("c".to_string()),
        Just("#".to_string()),
        Just("# V3".to_string()),
        Just("#V2".to_string()),
        Just("t rt".to_string()),
        Just("MAXVOLSELECTION".to_string()),
        Just("-1".to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("1e308".to_string()),
        Just("1/2/3".to_string()),
        Just("//".to_string()),
        Just("18446744073709551616".to_string()),
        (-5i64..6).prop_map(|i| i.to_string()),
        (-10.0f64..10.0).prop_map(|x| x.to_string()),
    ];
    let line = prop::collection::vec(token, 0..18).prop_map(|t| t.join(" "));
    prop::collection::vec(line, 0..30).prop_map(|lines| lines.join("\n").into_bytes())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(data in prop::collection::vec(any::<u8>(), 0..400)) {
        run_all(&data);
    }

    #[test]
    fn token_soup_never_panics(data in token_soup()) {
        run_all(&data);
    }

    #[test]
    fn obj_write_read_is_bit_exact(
        coords in prop::collection::vec(
            any::<f64>().prop_filter("an input value (finite, |x| ≤ 1e12)", |x| cagerig::error::is_input_value(*x)),
            9..60,
        ),
        tri_seed in prop::collection::vec(any::<u32>(), 3..30),
    ) {
        let positions: Vec<DVec3> = coords.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
        let n = positions.len() as u32;
        let triangles: Vec<[u32; 3]> = tri_seed.chunks_exact(3).map(|t| [t[0] % n, t[1] % n, t[2] % n]).collect();
        let mut bytes = Vec::new();
        io::obj::write_obj_to(&mut bytes, &positions, &triangles, io::FloatFormat::RoundTrip).unwrap();
        let mesh = io::parse_obj(&bytes, Path::new("mem")).unwrap();
        prop_assert_eq!(&mesh.triangles, &triangles);
        for (a, b) in mesh.positions.iter().zip(&positions) {
            for k in 0..3 {
                prop_assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
    }
}

//! Per-frame timings of LBS / DQS / CoR, f64 and f32 kernels, on
//! (1) a synthetic rig (133 073 vertices × 25 joints, 1–7 random influences per vertex) and
//! (2) the Arm subdivided 3 times (133 073 vertices, reference step-ii pose).
//! Run with `cargo run --release -p cagerig --example skinning_bench [repetitions] [kernel filter]
//! [Arm subdivision levels, default 3]` (a filter of `-` keeps every kernel).

#![expect(clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::SkinWeights;
use cagerig::io::{read_obj, read_skt, read_skw};
use cagerig::skinning::{
    CorF32, CorF32Scratch, CorScratch, CorSkinning, DqsF32, DqsF32Scratch, DqsScratch,
    DualQuaternionSkinning, LbsF32, LbsF32Scratch, LinearBlendSkinning,
};
use cagerig::subdivide::subdivide_midpoint;
use glam::{DAffine3, DQuat, DVec3, Vec3};

const NUM_VERTICES: usize = 133_073;
const NUM_JOINTS: usize = 25;
const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");

/// Small deterministic generator (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Prints min and median (ms) of `repetitions` runs after 10 warm-up runs.
///
/// An optional second command-line argument keeps only the kernels whose label contains it
/// (e.g. `DQS f32`), so that one kernel can be profiled on its own (`perf stat`).
fn time(label: &str, repetitions: usize, mut f: impl FnMut()) {
    if std::env::args()
        .nth(2)
        .is_some_and(|filter| filter != "-" && !label.contains(&filter))
    {
        return;
    }
    for _ in 0..10 {
        f();
    }
    let mut times: Vec<f64> = (0..repetitions)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "  {label}: min {:.3} ms, median {:.3} ms",
        times[0],
        times[repetitions / 2]
    );
}

fn bench(
    repetitions: usize,
    weights: &SkinWeights,
    transforms: &[DAffine3],
    rest: &[DVec3],
    centres: &[DVec3],
) {
    let n = rest.len();
    let num_joints = transforms.len();
    println!(
        "{n} vertices, {num_joints} joints, {} influences (max {}), {} rayon threads, {repetitions} runs",
        weights.num_entries(),
        weights.max_influences(),
        rayon::current_num_threads()
    );
    let mut out = vec![DVec3::ZERO; n];
    let mut out_f32 = vec![Vec3::ZERO; n];

    let lbs = LinearBlendSkinning::new(weights);
    time("LBS f64", repetitions, || {
        lbs.apply(transforms, rest, &mut out)
    });
    let lbs = LbsF32::new(weights, rest).expect("LBS f32");
    let mut scratch = LbsF32Scratch::new(num_joints);
    time("LBS f32", repetitions, || {
        lbs.apply(transforms, &mut scratch, &mut out_f32)
    });

    let dqs = DualQuaternionSkinning::new(weights);
    let mut scratch = DqsScratch::new(num_joints);
    time("DQS f64", repetitions, || {
        dqs.apply(transforms, rest, &mut scratch, &mut out)
    });
    let dqs = DqsF32::new(weights, rest).expect("DQS f32");
    let mut scratch = DqsF32Scratch::new(num_joints);
    time("DQS f32", repetitions, || {
        dqs.apply(transforms, &mut scratch, &mut out_f32)
    });

    let cor = CorSkinning::new(weights);
    let mut scratch = CorScratch::new(num_joints);
    time("CoR f64", repetitions, || {
        cor.apply(transforms, rest, centres, &mut scratch, &mut out)
    });
    let cor = CorF32::new(weights, rest, centres).expect("CoR f32");
    let mut scratch = CorF32Scratch::new(num_joints);
    time("CoR f32", repetitions, || {
        cor.apply(transforms, &mut scratch, &mut out_f32)
    });
}

fn synthetic(repetitions: usize) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let rest: Vec<DVec3> = (0..NUM_VERTICES)
        .map(|_| DVec3::new(rng.next(), rng.next(), rng.next()) * 100.0)
        .collect();
    // Each vertex: 1..=7 consecutive joints around a base joint (locality like a real rig).
    let mut triplets = Vec::new();
    for v in 0..NUM_VERTICES {
        let base = v * NUM_JOINTS / NUM_VERTICES;
        let count = 1 + (rng.next() * 7.0) as usize;
        for k in 0..count.min(7) {
            triplets.push((v, (base + k) % NUM_JOINTS, 0.05 + rng.next()));
        }
    }
    let (weights, _) =
        SkinWeights::from_triplets(NUM_VERTICES, NUM_JOINTS, triplets).expect("weights");
    let transforms: Vec<DAffine3> = (0..NUM_JOINTS)
        .map(|_| {
            let q = DQuat::from_xyzw(
                rng.next() - 0.5,
                rng.next() - 0.5,
                rng.next() - 0.5,
                rng.next() - 0.5,
            )
            .normalize();
            DAffine3::from_rotation_translation(q, DVec3::new(rng.next(), rng.next(), rng.next()))
        })
        .collect();
    let centres: Vec<DVec3> = rest.iter().map(|p| *p + DVec3::splat(0.5)).collect();
    println!("Synthetic rig:");
    bench(repetitions, &weights, &transforms, &rest, &centres);
}

fn subdivided_arm(repetitions: usize, levels: usize) {
    let dir = Path::new(ARM);
    let mesh = read_obj(&dir.join("arm.obj")).expect("arm.obj");
    let skeleton = read_skt(&dir.join("arm.skt")).expect("arm.skt");
    let (weights, _) =
        read_skw(&dir.join("arm.skw"), mesh.num_vertices(), skeleton.len()).expect("arm.skw");
    let sub = subdivide_midpoint(&mesh, &weights, levels).expect("subdivision");
    // Step ii: joint 3 rotated by 60° about world +X around its own position; FK to descendants.
    let rest_world = skeleton.rest_world_from_joint();
    let mut posed_world = rest_world.clone();
    let pivot = rest_world[3].translation;
    let rotation = DAffine3::from_translation(pivot)
        * DAffine3::from_rotation_x(60f64.to_radians())
        * DAffine3::from_translation(-pivot);
    for (j, world) in posed_world.iter_mut().enumerate() {
        let mut a = Some(j);
        while let Some(k) = a {
            if k == 3 {
                *world = rotation * *world;
                break;
            }
            a = skeleton.parent(k);
        }
    }
    let mut transforms = vec![DAffine3::IDENTITY; skeleton.len()];
    cagerig::Skeleton::skinning_transforms(&rest_world, &posed_world, &mut transforms);
    // CoR centres: the rest positions shifted a little (timing does not depend on their values).
    let rest = sub.mesh.positions;
    let centres: Vec<DVec3> = rest.iter().map(|p| *p + DVec3::splat(0.5)).collect();
    println!("Arm subdivided {levels} times, step ii:");
    bench(repetitions, &sub.skin_weights, &transforms, &rest, &centres);
}

fn main() {
    let repetitions = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(300usize)
        .max(1);
    let levels = std::env::args()
        .nth(3)
        .and_then(|a| a.parse().ok())
        .unwrap_or(3usize);
    if levels == 3 {
        synthetic(repetitions);
    }
    subdivided_arm(repetitions, levels);
}

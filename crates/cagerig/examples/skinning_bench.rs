//! Per-frame timings of LBS / DQS / CoR on a synthetic rig (~133k vertices × 25 joints,
//! ≤7 influences per vertex). Run with `cargo run --release -p cagerig --example skinning_bench`.

use std::time::Instant;

use cagerig::SkinWeights;
use cagerig::skinning::{
    CorScratch, CorSkinning, DqsScratch, DualQuaternionSkinning, LinearBlendSkinning,
};
use glam::{DAffine3, DQuat, DVec3};

const NUM_VERTICES: usize = 133_073;
const NUM_JOINTS: usize = 25;
const REPETITIONS: usize = 200;

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

fn median_ms(mut f: impl FnMut()) -> (f64, f64) {
    f();
    let mut times: Vec<f64> = (0..REPETITIONS)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (times[REPETITIONS / 2], times[0])
}

fn main() {
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
    let (weights, _) = SkinWeights::from_triplets(NUM_VERTICES, NUM_JOINTS, triplets).unwrap();
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
    let mut out = vec![DVec3::ZERO; NUM_VERTICES];

    println!(
        "{NUM_VERTICES} vertices, {NUM_JOINTS} joints, {} influences (max {}), {} rayon threads",
        weights.num_entries(),
        weights.max_influences(),
        rayon::current_num_threads()
    );
    let lbs = LinearBlendSkinning::new(&weights);
    let (med, min) = median_ms(|| lbs.apply(&transforms, &rest, &mut out));
    println!("LBS f64: median {med:.3} ms, min {min:.3} ms");
    let dqs = DualQuaternionSkinning::new(&weights);
    let mut dqs_scratch = DqsScratch::new(NUM_JOINTS);
    let (med, min) = median_ms(|| dqs.apply(&transforms, &rest, &mut dqs_scratch, &mut out));
    println!("DQS f64: median {med:.3} ms, min {min:.3} ms");
    let cor = CorSkinning::new(&weights);
    let mut cor_scratch = CorScratch::new(NUM_JOINTS);
    let (med, min) =
        median_ms(|| cor.apply(&transforms, &rest, &centres, &mut cor_scratch, &mut out));
    println!("CoR f64: median {med:.3} ms, min {min:.3} ms");
}

//! Skinning kernels and CoR centres on the Arm rig against the reference tool's outputs.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::time::Instant;

use cagerig::SkinWeights;
use cagerig::mesh::{bounding_box, max_distance};
use cagerig::skinning::{
    CorCentresFactored, CorCentresMethod, CorCentresOptions, CorScratch, CorSkinning, DqsScratch,
    DualQuaternionSkinning, LinearBlendSkinning, compute_cor_centres, compute_cor_centres_factored,
};
use cagerig::sparse_rows::SparseRows;
use glam::DVec3;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::{numbers, obj, read, step2_transforms};

fn weights(num_vertices: usize) -> SkinWeights {
    let text = read("arm.skw");
    let triplets: Vec<_> = text
        .lines()
        .map(|l| {
            let n = numbers(l);
            (n[1] as usize, n[0] as usize, n[2])
        })
        .collect();
    SkinWeights::from_triplets(num_vertices, 25, triplets)
        .unwrap()
        .0
}

fn reference_cor_matrix(num_vertices: usize) -> SparseRows {
    let triplets: Vec<_> = read("arm_corWeights.txt")
        .lines()
        .map(|l| {
            let n = numbers(l);
            (n[0] as usize, n[1] as usize, n[2])
        })
        .collect();
    SparseRows::from_triplets(num_vertices, num_vertices, triplets).unwrap()
}

fn diagonal(p: &[DVec3]) -> f64 {
    let (lo, hi) = bounding_box(p);
    lo.distance(hi)
}

#[test]
fn lbs_dqs_cor_match_reference_step2() {
    let (rest, _) = obj("arm.obj");
    let w = weights(rest.len());
    let t = step2_transforms();
    let n = rest.len();
    let mut out = vec![DVec3::ZERO; n];

    LinearBlendSkinning::new(&w).apply(&t, &rest, &mut out);
    let lbs_err = max_distance(&out, &obj("reference/s2_Mdef.obj").0);
    println!("LBS vs reference s2_Mdef: {lbs_err:e}");
    assert!(lbs_err < 1e-9);

    let mut scratch = DqsScratch::new(t.len());
    DualQuaternionSkinning::new(&w).apply(&t, &rest, &mut scratch, &mut out);
    let dqs_err = max_distance(&out, &obj("reference/extras/x_step2_DQS_Mdef.obj").0);
    println!("DQS vs reference x_step2_DQS_Mdef: {dqs_err:e}");
    assert!(dqs_err < 1e-9);

    // CoR with the reference's own centres (its S applied to M).
    let s_ref = reference_cor_matrix(n);
    let mut centres = vec![DVec3::ZERO; n];
    s_ref.apply(&rest, &mut centres);
    let mut scratch = CorScratch::new(t.len());
    CorSkinning::new(&w).apply(&t, &rest, &centres, &mut scratch, &mut out);
    let cor_err = max_distance(&out, &obj("reference/extras/x_step2_CoR_Mdef.obj").0);
    println!("CoR vs reference x_step2_CoR_Mdef: {cor_err:e}");
    // The reference forms its centres as (S·Φ)·C with Φ stored to 6 decimals.
    assert!(cor_err < 1e-3, "{cor_err}");
}

#[test]
fn cor_centres_exact_clustered_and_reference() {
    let (rest, tris) = obj("arm.obj");
    let w = weights(rest.len());
    let n = rest.len();
    let diag = diagonal(&rest);
    let centres_of = |s: &SparseRows| {
        let mut c = vec![DVec3::ZERO; n];
        s.apply(&rest, &mut c);
        c
    };

    let unpruned = CorCentresOptions {
        mass_tolerance: 0.0,
        ..Default::default()
    };
    let start = Instant::now();
    let s_full = compute_cor_centres(&rest, &tris, &w, &unpruned, &|_, _| {}).unwrap();
    let t_full = start.elapsed();
    let start = Instant::now();
    let s_exact =
        compute_cor_centres(&rest, &tris, &w, &CorCentresOptions::default(), &|_, _| {}).unwrap();
    let t_exact = start.elapsed();
    let full = centres_of(&s_full);
    let exact = centres_of(&s_exact);
    let prune_err = max_distance(&full, &exact) / diag;
    println!(
        "Arm {} v: bbox diag {diag:.3}; unpruned {:?} nnz {}; pruned(1e-5) {:?} nnz {} (max row {}), error/diag {prune_err:e}",
        n,
        t_full,
        s_full.nnz(),
        t_exact,
        s_exact.nnz(),
        (0..n).map(|i| s_exact.row(i).0.len()).max().unwrap()
    );
    assert!(prune_err <= 1e-5);

    let start = Instant::now();
    let factored =
        compute_cor_centres_factored(&rest, &tris, &w, &CorCentresOptions::default(), &|_, _| {})
            .unwrap();
    println!(
        "exact factored: {:?}, {} clusters, {} patches, nnz A {} + B {}",
        start.elapsed(),
        factored.num_clusters(),
        factored.num_patches(),
        factored.cluster_patch_weights.nnz(),
        factored.patch_points.nnz()
    );
    let factored_centres = |f: &CorCentresFactored| {
        let mut patch_scratch = vec![DVec3::ZERO; f.num_patches()];
        let mut cluster_scratch = vec![DVec3::ZERO; f.num_clusters()];
        let mut c = vec![DVec3::ZERO; n];
        f.apply(&rest, &mut patch_scratch, &mut cluster_scratch, &mut c);
        c
    };
    assert!(max_distance(&exact, &factored_centres(&factored)) < 1e-12 * diag);

    for step in [0.05, 0.02, 0.01, 0.005] {
        let options = CorCentresOptions {
            method: CorCentresMethod::Clustered {
                vertex_step: step,
                patch_step: 0.05,
                weight_floor: 0.0,
            },
            ..Default::default()
        };
        let start = Instant::now();
        let f = compute_cor_centres_factored(&rest, &tris, &w, &options, &|_, _| {}).unwrap();
        let elapsed = start.elapsed();
        let err = max_distance(&exact, &factored_centres(&f)) / diag;
        println!(
            "clustered vertex step {step}, patch step 0.05: {elapsed:?}, {} clusters, {} patches, nnz A {}, max error/diag {err:e}",
            f.num_clusters(),
            f.num_patches(),
            f.cluster_patch_weights.nnz()
        );
        if step <= 0.01 {
            assert!(err <= 1e-3, "step {step}: {err}");
        }
    }

    // Against the tool's offline CoR weights.
    let reference = centres_of(&reference_cor_matrix(n));
    let mut d: Vec<f64> = (0..n)
        .map(|i| reference[i].distance(exact[i]) / diag)
        .collect();
    let multi: Vec<f64> = (0..n)
        .filter(|&i| w.row(i).0.len() >= 2)
        .map(|i| reference[i].distance(exact[i]) / diag)
        .collect();
    d.sort_by(f64::total_cmp);
    let mut m = multi.clone();
    m.sort_by(f64::total_cmp);
    println!(
        "vs arm_corWeights (distance/diag): all median {:.3e} p90 {:.3e} max {:.3e}; multi-influence ({}) median {:.3e} p90 {:.3e} max {:.3e}",
        d[n / 2],
        d[n * 9 / 10],
        d[n - 1],
        m.len(),
        m[m.len() / 2],
        m[m.len() * 9 / 10],
        m[m.len() - 1]
    );
    assert!(m[m.len() / 2] < 0.02, "median {}", m[m.len() / 2]);

    // Effect on the step-ii CoR deformation: ours vs the tool's centres.
    let t = step2_transforms();
    let cor = CorSkinning::new(&w);
    let mut scratch = CorScratch::new(t.len());
    let mut ours = vec![DVec3::ZERO; n];
    let mut theirs = vec![DVec3::ZERO; n];
    cor.apply(&t, &rest, &exact, &mut scratch, &mut ours);
    cor.apply(&t, &rest, &reference, &mut scratch, &mut theirs);
    let deform_diff = max_distance(&ours, &theirs) / diag;
    println!("step ii CoR deformation, our centres vs arm_corWeights: max {deform_diff:e} of diag");
    assert!(deform_diff < 0.02);
}

type WeightRows = Vec<Vec<(usize, f64)>>;

/// Midpoint subdivision (1 → 4 triangles) with weights averaged on new edge vertices.
fn subdivide(
    rest: &[DVec3],
    tris: &[[u32; 3]],
    rows: &[Vec<(usize, f64)>],
) -> (Vec<DVec3>, Vec<[u32; 3]>, WeightRows) {
    let mut p = rest.to_vec();
    let mut r = rows.to_vec();
    let mut edge_vertex = std::collections::HashMap::new();
    let mut midpoint = |a: u32, b: u32, p: &mut Vec<DVec3>, r: &mut Vec<Vec<(usize, f64)>>| {
        *edge_vertex.entry((a.min(b), a.max(b))).or_insert_with(|| {
            p.push((p[a as usize] + p[b as usize]) * 0.5);
            let mut m = std::collections::BTreeMap::new();
            for &(j, x) in r[a as usize].iter().chain(&r[b as usize]) {
                *m.entry(j).or_insert(0.0) += 0.5 * x;
            }
            r.push(m.into_iter().collect());
            (p.len() - 1) as u32
        })
    };
    let mut t = Vec::with_capacity(tris.len() * 4);
    for &[a, b, c] in tris {
        let ab = midpoint(a, b, &mut p, &mut r);
        let bc = midpoint(b, c, &mut p, &mut r);
        let ca = midpoint(c, a, &mut p, &mut r);
        t.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    (p, t, r)
}

/// Scaling of the CoR centre computation on subdivided Arms (prints; run with --ignored).
#[test]
#[ignore]
fn cor_centres_on_subdivided_arm() {
    let (mut rest, mut tris) = obj("arm.obj");
    let w = weights(rest.len());
    let mut rows: Vec<Vec<(usize, f64)>> = (0..rest.len())
        .map(|v| {
            let (j, x) = w.row(v);
            j.iter()
                .map(|&j| j as usize)
                .zip(x.iter().copied())
                .collect()
        })
        .collect();
    for level in 1..=2 {
        (rest, tris, rows) = subdivide(&rest, &tris, &rows);
        let n = rest.len();
        let triplets: Vec<_> = rows
            .iter()
            .enumerate()
            .flat_map(|(v, r)| r.iter().map(move |&(j, x)| (v, j, x)))
            .collect();
        let w = SkinWeights::from_triplets(n, 25, triplets).unwrap().0;
        let diag = diagonal(&rest);
        let centres = |f: &CorCentresFactored| {
            let mut a = vec![DVec3::ZERO; f.num_patches()];
            let mut b = vec![DVec3::ZERO; f.num_clusters()];
            let mut c = vec![DVec3::ZERO; n];
            f.apply(&rest, &mut a, &mut b, &mut c);
            c
        };
        let env = |name: &str, default: f64| {
            std::env::var(name)
                .ok()
                .and_then(|x| x.parse().ok())
                .unwrap_or(default)
        };
        let options = CorCentresOptions {
            method: CorCentresMethod::Clustered {
                vertex_step: env("VSTEP", 0.01),
                patch_step: env("PSTEP", 0.05),
                weight_floor: env("FLOOR", 0.0),
            },
            mass_tolerance: env("MASSTOL", 1e-5),
            ..Default::default()
        };
        if level > env("LEVELS", 2.0) as usize {
            break;
        }
        let start = Instant::now();
        let clustered =
            compute_cor_centres_factored(&rest, &tris, &w, &options, &|_, _| {}).unwrap();
        let t_clustered = start.elapsed();
        let mut patch_scratch = vec![DVec3::ZERO; clustered.num_patches()];
        let mut cluster_scratch = vec![DVec3::ZERO; clustered.num_clusters()];
        let mut out = vec![DVec3::ZERO; n];
        let start = Instant::now();
        clustered.apply(&rest, &mut patch_scratch, &mut cluster_scratch, &mut out);
        let t_apply = start.elapsed();
        println!(
            "level {level}: {n} v, {} tris; clustered {:?} {t_clustered:?}: {} clusters, {} patches, nnz A {}, B {}; CoR update (A·(B·M)) {t_apply:?}",
            tris.len(),
            options.method,
            clustered.num_clusters(),
            clustered.num_patches(),
            clustered.cluster_patch_weights.nnz(),
            clustered.patch_points.nnz()
        );
        if level == 1 {
            let start = Instant::now();
            let exact = compute_cor_centres_factored(
                &rest,
                &tris,
                &w,
                &CorCentresOptions::default(),
                &|_, _| {},
            )
            .unwrap();
            println!(
                "level 1 exact: {:?}, nnz A {}; clustered max error/diag {:e}",
                start.elapsed(),
                exact.cluster_patch_weights.nnz(),
                max_distance(&centres(&exact), &centres(&clustered)) / diag
            );
            if options.method
                == (CorCentresMethod::Clustered {
                    vertex_step: 0.01,
                    patch_step: 0.05,
                    weight_floor: 0.0,
                })
            {
                let err = max_distance(&centres(&exact), &centres(&clustered)) / diag;
                assert!(err < 1e-3, "{err}");
            }
        }
    }
}

/// Λ = S·Φ computed directly (clustered, as the session does on big meshes): Λ·C against the
/// exact Eq. 5 centres, and partition of unity of Λ's rows.
#[test]
fn cor_cage_coords_on_arm() {
    let (rest, tris) = obj("arm.obj");
    let (cage, cage_tris) = obj("arm_cage.obj");
    let w = weights(rest.len());
    let n = rest.len();
    let diag = diagonal(&rest);
    let cage_mesh = cagerig::TriMesh::new(cage.clone(), cage_tris).unwrap();
    let phi = cagerig::coords::mvc::compute_cage_coords(&cage_mesh, &rest, None).unwrap();
    let unpruned = CorCentresOptions {
        mass_tolerance: 0.0,
        ..Default::default()
    };
    let s = compute_cor_centres(&rest, &tris, &w, &unpruned, &|_, _| {}).unwrap();
    let mut exact = vec![DVec3::ZERO; n];
    s.apply(&rest, &mut exact);
    let options = CorCentresOptions {
        method: CorCentresMethod::Clustered {
            vertex_step: 0.01,
            patch_step: 0.05,
            weight_floor: 0.0,
        },
        ..Default::default()
    };
    let start = Instant::now();
    let lambda =
        cagerig::skinning::compute_cor_cage_coords(&rest, &tris, &w, &phi, &options, &|_, _| {})
            .unwrap();
    let elapsed = start.elapsed();
    let mut centres = vec![DVec3::ZERO; n];
    lambda.apply(&cage, &mut centres);
    let err = max_distance(&exact, &centres) / diag;
    println!("Arm Λ (clustered): {elapsed:?}, max centre error {err:e} of bbox diagonal");
    assert!(err <= 1e-3, "{err}");
    for i in 0..n {
        let sum: f64 = (0..lambda.num_cage_vertices())
            .map(|k| lambda.get(i, k))
            .sum();
        assert!((sum - 1.0).abs() < 1e-9, "{i}: {sum}");
    }
}

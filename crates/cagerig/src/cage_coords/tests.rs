//! Tests of [`super::CageCoords`]: the products against plain references, bit for bit.

use super::*;

#[test]
fn f32_storage_gives_the_f64_products_of_the_rounded_coordinates() {
    let (nv, nc) = (1500, 7);
    let matrix = Mat::from_fn(nv, nc, |i, k| {
        ((i * 31 + k * 17) % 101) as f64 / 707.0 + 1e-9
    });
    let mut rounded = CageCoords::from_matrix(matrix.clone()).unwrap();
    rounded.round_to_f32();
    assert_eq!(rounded.precision(), CoordsPrecision::F32);
    // Entries moved by at most half an f32 ulp.
    for k in 0..nc {
        for i in 0..nv {
            let (a, b) = (matrix[(i, k)], rounded.get(i, k));
            assert!((a - b).abs() <= a.abs() * 2f64.powi(-24));
        }
    }
    // The f64 path on the rounded values and the f32 path agree bit for bit.
    let f64_path = CageCoords::from_matrix(rounded.matrix().clone()).unwrap();
    assert_eq!(f64_path.precision(), CoordsPrecision::F64);
    let cage: Vec<DVec3> = (0..nc)
        .map(|k| DVec3::new(k as f64 * 0.3, 1.0 - k as f64, 0.25 * (k * k) as f64))
        .collect();
    let (mut a, mut b) = (vec![DVec3::ZERO; nv], vec![DVec3::ZERO; nv]);
    rounded.apply(&cage, &mut a);
    f64_path.apply(&cage, &mut b);
    assert_eq!(a, b);
    let (vertices, deltas) = (
        [5usize, 0, 3],
        [DVec3::X, DVec3::new(0.1, -2.0, 3.0), DVec3::Z],
    );
    rounded.apply_delta(&vertices, &deltas, &mut a);
    f64_path.apply_delta(&vertices, &deltas, &mut b);
    assert_eq!(a, b);
    // Rounding twice changes nothing.
    let again = rounded.clone();
    rounded.round_to_f32();
    assert_eq!(rounded, again);
}

#[test]
fn apply_matches_the_plain_product_for_any_number_of_columns() {
    // Tiles of LANE_BLOCK rows, eight- and four-column groups and remainders: 1..=17
    // columns, odd #V.
    for nc in 1..=17 {
        let nv = 2 * ROW_BLOCK + LANE_BLOCK + 3;
        let matrix = Mat::from_fn(nv, nc, |i, k| ((i * 7 + k * 13) % 23) as f64 - 11.0);
        let phi = CageCoords::from_matrix(matrix.clone()).unwrap();
        let cage: Vec<DVec3> = (0..nc)
            .map(|k| DVec3::new(k as f64 + 1.0, 2.0 - k as f64, 0.5))
            .collect();
        let mut out = vec![DVec3::splat(99.0); nv];
        phi.apply(&cage, &mut out);
        for (i, o) in out.iter().enumerate() {
            let expected = (0..nc).fold(DVec3::ZERO, |acc, k| acc + matrix[(i, k)] * cage[k]);
            // Small integers times small integers: exact in any summation order.
            assert_eq!(*o, expected, "row {i}, {nc} columns");
        }
    }
}

/// `s + Σ_c w_c d_c` over one group as the products add it: the group's own chain of fused
/// multiply-adds from `w₀·d₀`, added to `s`.
fn group_reference(s: f64, w: &[f64], d: &[f64]) -> f64 {
    let t = (1..w.len()).fold(w[0] * d[0], |t, c| w[c].mul_add(d[c], t));
    s + t
}

#[test]
fn every_product_adds_its_groups_as_fused_chains_in_column_order() {
    // The expected values come from `mul_add` in this test's baseline code (libm's
    // correctly rounded fma); `apply` runs the widest tier this CPU has and `apply_rows` its
    // own dispatch: the same bits prove every tier and both products add the groups of
    // eight, four and one columns (13 = 8 + 4 + 1) in order as `group_reference`; f64 and
    // f32 storage.
    let (nv, nc) = (LANE_BLOCK + 77, 13);
    let mut phi = varied(nv, nc, 5);
    let cage: Vec<DVec3> = (0..nc)
        .map(|k| {
            DVec3::new(
                0.1 * k as f64 + 0.37,
                1.3 - k as f64 / 7.0,
                2.9 / (k + 1) as f64,
            )
        })
        .collect();
    for round in [false, true] {
        if round {
            phi.round_to_f32();
        }
        let expected: Vec<DVec3> = (0..nv)
            .map(|i| {
                let mut s = [0.0; 3];
                for group in [0..8, 8..12, 12..13] {
                    let w: Vec<f64> = group.clone().map(|k| phi.get(i, k)).collect();
                    for (a, sum) in s.iter_mut().enumerate() {
                        let d: Vec<f64> = group.clone().map(|k| cage[k][a]).collect();
                        *sum = group_reference(*sum, &w, &d);
                    }
                }
                DVec3::from_array(s)
            })
            .collect();
        let mut out = vec![DVec3::NAN; nv];
        phi.apply(&cage, &mut out);
        assert_eq!(out, expected, "f32 storage {round}");
        let rows = [0, 5, LANE_BLOCK, nv - 1];
        let mut picked = vec![DVec3::NAN; rows.len()];
        phi.apply_rows(&rows, &cage, &mut picked);
        for (r, &row) in rows.iter().enumerate() {
            assert_eq!(picked[r], expected[row], "row {row}, f32 storage {round}");
        }
    }
}

#[test]
fn apply_and_delta_agree() {
    let rows: Vec<Vec<f64>> = (0..10_000)
        .map(|i| {
            let a = (i % 7) as f64 / 7.0;
            vec![a, 0.5 - a / 2.0, 0.5 - a / 2.0]
        })
        .collect();
    let phi = CageCoords::from_rows(&rows, 3).unwrap();
    let cage = vec![DVec3::X, DVec3::Y, DVec3::new(1.0, 2.0, 3.0)];
    let mut m = vec![DVec3::ZERO; rows.len()];
    phi.apply(&cage, &mut m);
    let i = 5000;
    let expect = rows[i][0] * cage[0] + rows[i][1] * cage[1] + rows[i][2] * cage[2];
    assert!(m[i].abs_diff_eq(expect, 1e-15));
    let mut moved = cage.clone();
    moved[2] += DVec3::new(0.5, -1.0, 2.0);
    phi.apply_delta(&[2], &[DVec3::new(0.5, -1.0, 2.0)], &mut m);
    let mut full = vec![DVec3::ZERO; rows.len()];
    phi.apply(&moved, &mut full);
    assert!(crate::mesh::max_distance(&m, &full) < 1e-14);
    assert!(matches!(
        CageCoords::from_rows(&[vec![1.0]], 2),
        Err(RigError::SizeMismatch { .. })
    ));
}

#[test]
fn apply_rows_gives_the_bits_of_apply() {
    // Column counts with and without a group of four or single columns after the groups of
    // eight (58: the Arm's cage, 7 × 8 + 2).
    for nc in [3, 4, 7, 8, 9, 13, 15, 58] {
        let nv = 9000;
        let matrix = Mat::from_fn(nv, nc, |i, k| {
            (((i * 7919 + k * 104_729) % 1013) as f64 / 1013.0 - 0.3) * 1.1f64.powi(k as i32)
        });
        let mut phi = CageCoords::from_matrix(matrix).unwrap();
        let cage: Vec<DVec3> = (0..nc)
            .map(|k| DVec3::new(0.1 * k as f64 + 0.37, 1.3 - k as f64 / 7.0, 2.9))
            .collect();
        for round in [false, true] {
            if round {
                phi.round_to_f32();
            }
            let mut full = vec![DVec3::ZERO; nv];
            phi.apply(&cage, &mut full);
            let rows = [0, 1, 511, 512, 4095, 4096, 8999, 17];
            let mut picked = vec![DVec3::NAN; rows.len()];
            phi.apply_rows(&rows, &cage, &mut picked);
            for (r, &row) in rows.iter().enumerate() {
                assert_eq!(picked[r], full[row], "{nc} columns, row {row}, f32 {round}");
            }
            // The rows selected as coordinates of their own: the same bits again, and
            // add_rows on top of them as on the full coordinates.
            let selected = phi.rows_as_coords(&rows);
            let identity: Vec<usize> = (0..rows.len()).collect();
            let mut from_selected = vec![DVec3::NAN; rows.len()];
            selected.apply_rows(&identity, &cage, &mut from_selected);
            assert_eq!(from_selected, picked, "{nc} columns, f32 {round}");
            phi.add_rows(&rows, &cage, &mut picked);
            selected.add_rows(&identity, &cage, &mut from_selected);
            assert_eq!(from_selected, picked, "{nc} columns, f32 {round}");
        }
    }
}

/// A test matrix whose entries differ from column to column and row to row.
fn varied(nv: usize, nc: usize, seed: usize) -> CageCoords {
    CageCoords::from_matrix(Mat::from_fn(nv, nc, |i, k| {
        (((i * 7919 + k * 104_729 + seed * 31) % 1013) as f64 / 1013.0 - 0.3)
            * 1.07f64.powi(k as i32)
    }))
    .unwrap()
}

#[test]
fn the_one_pass_product_with_extra_columns_gives_the_bits_of_two_passes() {
    // Φ with a partial group at its end (58 = 7 × 8 + 2) and Ψ of 112 and 5 columns, over
    // a row count that ends in a partial tile and a partial row block; each of Φ and Ψ in
    // f64 or rounded to f32 (the mixed cases take the two passes). A sparse edit of both in
    // one pass gives the bits of the two edits in turn too.
    let nv = 2 * ROW_BLOCK + LANE_BLOCK + 37;
    for (nc, nf) in [(58, 112), (9, 5)] {
        for (round_phi, round_psi) in [(false, false), (true, true), (true, false), (false, true)] {
            let mut phi = varied(nv, nc, 1);
            let mut psi = varied(nv, nf, 2);
            if round_phi {
                phi.round_to_f32();
            }
            if round_psi {
                psi.round_to_f32();
            }
            let cage: Vec<DVec3> = (0..nc)
                .map(|k| DVec3::new(0.1 * k as f64 + 0.37, 1.3 - k as f64 / 7.0, 2.9))
                .collect();
            let terms: Vec<DVec3> = (0..nf)
                .map(|f| DVec3::new(-0.2 * f as f64, 0.03 * f as f64 + 1.0, 0.7))
                .collect();
            let mut two_passes = vec![DVec3::ZERO; nv];
            phi.apply(&cage, &mut two_passes);
            let all: Vec<usize> = (0..nf).collect();
            psi.apply_delta(&all, &terms, &mut two_passes);
            let mut one_pass = vec![DVec3::NAN; nv];
            phi.apply_with_extra(&cage, &psi, &terms, &mut one_pass);
            let case = format!("{nc} + {nf} columns, f32 {round_phi}/{round_psi}");
            assert_eq!(one_pass, two_passes, "{case}");
            // The tiles handed on: every row once, holding its final value.
            let mut seen = vec![DVec3::NAN; nv];
            let mut again = vec![DVec3::NAN; nv];
            phi.apply_then(
                &cage,
                Some((&psi, &terms)),
                &mut again,
                &mut seen,
                |first, rows, copy| {
                    assert!(rows.len() <= LANE_BLOCK && first % LANE_BLOCK == 0);
                    assert!(copy.iter().all(|p| p.is_nan()), "{first}: a row twice");
                    copy.copy_from_slice(rows);
                },
            );
            assert_eq!(again, two_passes, "{case}");
            assert_eq!(seen, two_passes, "{case}");
            // A sparse edit of a few columns of each: the bits of the two deltas in turn.
            let (vertices, faces) = ([nc - 1, 0, nc / 2], [nf / 3, nf - 1]);
            let deltas = [cage[1], -cage[2], cage[0]];
            let changes = [terms[0], -terms[nf - 1]];
            let mut two_deltas = two_passes.clone();
            phi.apply_delta(&vertices, &deltas, &mut two_deltas);
            psi.apply_delta(&faces, &changes, &mut two_deltas);
            let mut one_delta = two_passes.clone();
            phi.apply_delta_with_extra(&vertices, &deltas, &psi, &faces, &changes, &mut one_delta);
            assert_eq!(one_delta, two_deltas, "{case}: sparse edit");
            assert_ne!(one_delta, two_passes, "{case}: the edit moved nothing");
        }
    }
    // Without extra columns: the bits of apply.
    let phi = varied(nv, 58, 3);
    let cage = vec![DVec3::new(1.0, -2.0, 0.5); 58];
    let mut plain = vec![DVec3::ZERO; nv];
    phi.apply(&cage, &mut plain);
    let (mut out, mut seen) = (vec![DVec3::NAN; nv], vec![DVec3::NAN; nv]);
    phi.apply_then(&cage, None, &mut out, &mut seen, |_, rows, copy| {
        copy.copy_from_slice(rows)
    });
    assert_eq!((&out, &seen), (&plain, &plain));
}

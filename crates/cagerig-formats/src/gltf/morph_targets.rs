//! The morph targets of the skinned node that the animations animate, merged over its
//! primitives into `#targets × #V` world-space displacements (see
//! [`crate::character::MorphTargets`]).

use glam::DVec3;

/// A node's default morph weights: its own `weights`, else its mesh's (empty when neither).
pub(super) fn default_weights(node: &gltf::Node) -> Vec<f64> {
    node.weights()
        .or_else(|| node.mesh().and_then(|m| m.weights()))
        .map(|w| w.iter().map(|&x| f64::from(x)).collect())
        .unwrap_or_default()
}

/// Appends one primitive's target displacements (`primitive`: per target, `vertices` each) to
/// the merged targets, whose vertices so far number `base`; targets the primitive lacks get
/// zeros. The dense `#targets × #V` table is reserved first: a file declaring more targets
/// than memory holds is an error, not an abort.
pub(super) fn merge_targets(
    merged: &mut Vec<Vec<DVec3>>,
    primitive: &[Vec<DVec3>],
    base: usize,
    vertices: usize,
) -> Result<(), cagerig::RigError> {
    let count = merged.len().max(primitive.len());
    cagerig::memory_estimate::check_table_allocation(
        "morph targets (displacements per target and vertex)",
        count.saturating_mul(3),
        "target coordinates",
        base + vertices,
    )?;
    if merged.len() < primitive.len() {
        merged.resize(primitive.len(), Vec::new());
    }
    for (k, target) in merged.iter_mut().enumerate() {
        target.resize(base, DVec3::ZERO);
        match primitive.get(k) {
            Some(d) if d.len() == vertices => target.extend_from_slice(d),
            _ => target.resize(base + vertices, DVec3::ZERO),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_are_merged_with_zeros_where_a_target_is_missing() {
        let mut merged = Vec::new();
        // Primitive 1 (2 vertices): one target; primitive 2 (1 vertex): two targets.
        merge_targets(&mut merged, &[vec![DVec3::X, DVec3::Y]], 0, 2).unwrap();
        merge_targets(&mut merged, &[Vec::new(), vec![DVec3::Z]], 2, 1).unwrap();
        assert_eq!(
            merged,
            vec![
                vec![DVec3::X, DVec3::Y, DVec3::ZERO],
                vec![DVec3::ZERO, DVec3::ZERO, DVec3::Z],
            ]
        );
    }

    #[test]
    fn a_table_beyond_memory_is_an_error_before_any_allocation() {
        let mut merged = Vec::new();
        let targets = vec![Vec::new(); 100_000];
        let e = merge_targets(&mut merged, &targets, 1 << 40, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("morph targets"), "{e}");
        assert!(merged.is_empty());
    }
}

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

/// The first baked target of `mesh` and the method baked (its `extras.cagerig_baked_skinning`,
/// written by `cagerig export --bake`, see [`super::export_animation::animation_to_gltf`]),
/// or `None` when the mesh holds no baked targets.
pub(super) fn baked_targets(mesh: &gltf::Mesh) -> Option<(usize, String)> {
    let extras: serde_json::Value = serde_json::from_str(mesh.extras().as_ref()?.get()).ok()?;
    let baked = extras.get("cagerig_baked_skinning")?;
    let first = usize::try_from(baked.get("first_target")?.as_u64()?).ok()?;
    let name = baked
        .get("method")
        .and_then(serde_json::Value::as_str)
        .unwrap_or("skinning");
    let method = name
        .parse::<cagerig::skinning::SkinningMethod>()
        .map_or_else(|_| name.to_owned(), |m| m.label().to_owned());
    Some((first, method))
}

/// Leaves out the targets from `first` on (`targets`: `#targets × #V`, `default_weights`:
/// `#targets`), and their columns of each animation's morph weights (`#keys × #targets`,
/// row-major, `total` targets per key); an animation left with no target has no morph weights.
pub(super) fn drop_baked_targets(
    first: usize,
    total: usize,
    targets: &mut Vec<Vec<DVec3>>,
    default_weights: &mut Vec<f64>,
    animations: &mut [crate::character::ImportedAnimation],
) {
    let first = first.min(total);
    targets.truncate(first);
    default_weights.truncate(first);
    for animation in animations {
        animation.morph_weights = match animation.morph_weights.take() {
            Some(w) if first > 0 && total > 0 => Some(
                w.chunks_exact(total)
                    .flat_map(|row| row[..first].iter().copied())
                    .collect(),
            ),
            Some(_) | None => None,
        };
    }
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
    fn baked_targets_and_their_weight_columns_are_left_out() {
        let mut targets = vec![vec![DVec3::X], vec![DVec3::Y], vec![DVec3::Z]];
        let mut defaults = vec![0.0; 3];
        let track = cagerig::animation::SkeletonTrack::new(vec![0.0, 1.0], vec![vec![]; 2]);
        let animation = |weights: Vec<f64>| crate::character::ImportedAnimation {
            name: "a".into(),
            duration: 1.0,
            track: track.clone().unwrap(),
            exact: true,
            morph_weights: Some(weights),
        };
        // One cage target then two baked ones: key rows (cage, baked 0, baked 1).
        let mut animations = vec![animation(vec![0.5, 1.0, 0.0, 0.25, 0.0, 1.0])];
        drop_baked_targets(1, 3, &mut targets, &mut defaults, &mut animations);
        assert_eq!(targets, vec![vec![DVec3::X]]);
        assert_eq!(defaults, vec![0.0]);
        assert_eq!(animations[0].morph_weights, Some(vec![0.5, 0.25]));
        // Only baked targets: no morph weights remain.
        let mut animations = vec![animation(vec![1.0, 0.0, 0.0, 1.0])];
        drop_baked_targets(0, 2, &mut targets, &mut defaults, &mut animations);
        assert!(targets.is_empty() && animations[0].morph_weights.is_none());
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

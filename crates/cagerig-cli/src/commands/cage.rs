//! `cagerig cage`: generate a validated deformation cage for a mesh.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use cagerig::cage_gen::{
    CageLayout, CageOptions, CageReport, CageRequirements, CageRig, CageTarget, DEFAULT_MARGIN,
    DEFAULT_VERTICES, GeneratedCage, check_coordinates, generate_rig_cage, validate_cage_geometry,
};
use cagerig::cage_source::{RIG_CHECK, RigCheckDepth, generate_usable_cage, rig_check};
use cagerig::io::obj::{read_obj, write_obj};
use cagerig::{SkinWeights, TriMesh};
use serde::Serialize;

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Mesh to enclose: OBJ, or the skinned mesh of a glTF 2.0 (`.glb`/`.gltf`) or FBX file
    /// (its rest pose).
    #[arg(required_unless_present = "builtin")]
    pub mesh: Option<PathBuf>,
    /// Use the skin of a built-in demo rig instead of a file (bar, bar_irregular, snake).
    #[arg(long, conflicts_with = "mesh")]
    pub builtin: Option<String>,
    /// Target number of cage vertices (the result is exact, the validator allows ±10 %).
    #[arg(long, conflicts_with = "faces")]
    pub vertices: Option<usize>,
    /// Target number of cage triangles instead of vertices.
    #[arg(long)]
    pub faces: Option<usize>,
    /// Least distance from the mesh to the cage, as a fraction of the mesh's bounding-box
    /// diagonal.
    #[arg(long, default_value_t = DEFAULT_MARGIN)]
    pub margin: f64,
    /// How the cage is laid out when the mesh has a skeleton (a glTF/FBX skin, a built-in rig,
    /// or an OBJ with `<stem>.skt` beside it): by the skeleton (limbs kept apart by the skin's
    /// dominant joints, rings of vertices at the articulations) or one offset surface.
    #[arg(long, value_parser = crate::session_args::kind_parser::<CageLayout>(), default_value = CageLayout::default().name())]
    pub layout: CageLayout,
    /// Write the cage here (OBJ). Without it nothing is written.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct CageOutput<'a> {
    mesh: String,
    mesh_vertices: usize,
    mesh_triangles: usize,
    out: Option<&'a PathBuf>,
    passed: bool,
    cage: &'a CageReport,
    generation: &'a cagerig::cage_gen::offset_search::GenerationStats,
    /// Generation (search + geometric validation), then coordinates check and MaxVol, seconds.
    generation_seconds: f64,
    coordinates_seconds: f64,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (name, mesh, rig) = match (&args.builtin, &args.mesh) {
        (Some(name), _) => {
            let rig = cagerig::demo::builtin(name, None)
                .with_context(|| format!("building the built-in rig {name:?}"))?;
            (
                format!("builtin:{name}"),
                rig.mesh,
                Some((rig.skeleton, Some(rig.skin_weights))),
            )
        }
        (None, Some(path)) if crate::interchange::is_interchange(path)? => {
            let character = crate::interchange::import(path, None)?;
            (
                path.display().to_string(),
                character.mesh,
                Some((character.skeleton, Some(character.skin_weights))),
            )
        }
        (None, Some(path)) => {
            let mesh = read_obj(path).with_context(|| format!("reading {}", path.display()))?;
            let rig = obj_rig(path, &mesh)?;
            (path.display().to_string(), mesh, rig)
        }
        (None, None) => bail!("give a mesh file or --builtin NAME"),
    };
    let target = match (args.vertices, args.faces) {
        (_, Some(f)) => CageTarget::Faces(f),
        (Some(v), None) => CageTarget::Vertices(v),
        (None, None) => CageTarget::Vertices(DEFAULT_VERTICES),
    };
    let options = CageOptions {
        target,
        margin: args.margin,
        layout: args.layout,
    };
    let cage_rig = rig.as_ref().map(|(skeleton, weights)| CageRig {
        skeleton,
        weights: weights.as_ref(),
    });
    let start = Instant::now();
    let asked_for_a_size = args.vertices.is_some() || args.faces.is_some();
    let generated = if asked_for_a_size {
        // The size asked for, checked below as a rig will use it.
        generate_rig_cage(&mesh, &options, cage_rig)
            .with_context(|| format!("generating a cage for {name}"))?
    } else {
        // The default size, lowered to what a rig on this mesh can use (and said so).
        generate_usable_cage(
            Path::new(&name),
            &mesh,
            cage_rig,
            &options,
            RigCheckDepth::Always,
        )?
    };
    let GeneratedCage {
        cage,
        mut report,
        stats,
    } = generated;
    let generation_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    check_coordinates(&cage, &mesh, &mut report);
    if asked_for_a_size {
        report
            .checks
            .push(rig_check(&cage, &mesh, RigCheckDepth::Always));
    } else if let Some(lowered) = report
        .checks
        .iter()
        .find(|c| c.name == RIG_CHECK && c.detail.contains("instead of"))
    {
        eprintln!("note: {name}: {}", lowered.detail);
    }
    let coordinates_seconds = start.elapsed().as_secs_f64();
    if !report.passed() {
        // Generation validated the geometry; the coordinates and the rig's checks can fail here.
        bail!(
            "the cage for {name} failed validation: {}",
            report.failures().join("; ")
        );
    }
    if let Some(out) = &args.out {
        write_cage(out, &cage)?;
    }
    let output = CageOutput {
        mesh: name,
        mesh_vertices: mesh.num_vertices(),
        mesh_triangles: mesh.num_triangles(),
        out: args.out.as_ref(),
        passed: report.passed(),
        cage: &report,
        generation: &stats,
        generation_seconds,
        coordinates_seconds,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&output)?);
    } else {
        print_report(&output);
    }
    Ok(())
}

/// The skeleton (`<stem>.skt`) and skinning weights (`<stem>.skw`) beside an OBJ mesh, when
/// there is a skeleton: they lay the cage out by the body. Files that are there but cannot be
/// read are errors.
fn obj_rig(
    path: &Path,
    mesh: &TriMesh,
) -> anyhow::Result<Option<(cagerig::Skeleton, Option<SkinWeights>)>> {
    let found = cagerig::io::discovery::discover(path, None);
    let Some(skeleton_path) = found.skeleton else {
        return Ok(None);
    };
    let skeleton = cagerig::io::skt::read_skt(&skeleton_path)
        .with_context(|| format!("reading the skeleton {}", skeleton_path.display()))?;
    let weights = match found.skin_weights {
        Some(weights_path) => Some(
            cagerig::io::skw::read_skw_for_skeleton(
                &weights_path,
                mesh.num_vertices(),
                &skeleton,
                &skeleton_path.display().to_string(),
            )
            .with_context(|| format!("reading the skinning weights {}", weights_path.display()))?
            .0,
        ),
        None => None,
    };
    Ok(Some((skeleton, weights)))
}

fn write_cage(out: &Path, cage: &TriMesh) -> anyhow::Result<()> {
    write_obj(out, &cage.positions, &cage.triangles).context("writing the cage")
}

fn print_report(o: &CageOutput) {
    let r = o.cage;
    println!(
        "mesh           {} ({} vertices, {} triangles, {} piece(s))",
        o.mesh, o.mesh_vertices, o.mesh_triangles, o.generation.mesh_pieces
    );
    println!(
        "cage           {} vertices, {} triangles",
        r.cage_vertices, r.cage_faces
    );
    println!(
        "distance       min {:.3} %, mean {:.3} % of the diagonal (triangles: min {:.3} %)",
        100.0 * r.min_distance_fraction,
        100.0 * r.mean_distance_fraction,
        100.0 * r.min_triangle_distance_fraction
    );
    println!("volume ratio   {:.3} (cage / mesh)", r.volume_ratio);
    println!(
        "shape          smallest triangle angle {:.2}°",
        r.min_triangle_angle.to_degrees()
    );
    if let Some(c) = r.maxvol_condition {
        println!("MaxVol cond.   {c:.3e}");
    }
    match o.generation.layout {
        CageLayout::Skeleton => println!(
            "layout         skeleton: {} body parts, {} grid points cut between limbs, {} articulation rings",
            o.generation.body_parts, o.generation.cut_points, o.generation.articulation_rings
        ),
        CageLayout::Offset => println!("layout         offset"),
    }
    println!(
        "offset         {:.3} % of the diagonal (grid spacing {:.3} %, {} surface vertices simplified)",
        100.0 * o.generation.offset_fraction,
        100.0 * o.generation.spacing_fraction,
        o.generation.surface_vertices
    );
    println!(
        "time           {:.3} s generation, {:.3} s coordinates check",
        o.generation_seconds, o.coordinates_seconds
    );
    print_checks(r);
    match o.out {
        Some(p) => println!("written        {}", p.display()),
        None => println!("written        nothing (use --out CAGE.obj)"),
    }
}

/// The validator's geometric checks of a rig's cage against its mesh (for `info`): no margin is
/// required; the figures say how close the cage comes.
pub fn validate_rig_cage(cage: &TriMesh, mesh: &TriMesh) -> CageReport {
    let requirements = CageRequirements {
        margin: 0.0,
        target_vertices: None,
        target_faces: None,
    };
    validate_cage_geometry(cage, mesh, &requirements)
}

/// One line per check.
pub fn print_checks(r: &CageReport) {
    for c in &r.checks {
        println!(
            "check          {:<22} {}  {}",
            c.name,
            if c.passed { "ok  " } else { "FAIL" },
            c.detail
        );
    }
}

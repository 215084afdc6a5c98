//! `cagerig weights`: automatic skinning weights (geodesic voxel binding) written as `.skw`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use cagerig::auto_weights::{
    AutoWeights, AutoWeightsOptions, AutoWeightsReport, DEFAULT_EXPONENT, DEFAULT_MAX_INFLUENCES,
    DEFAULT_RESOLUTION, TipJoints,
};
use cagerig::io::obj::read_obj;
use cagerig::io::skt::read_skt;
use cagerig::io::skw::write_skw;
use cagerig::io::text::FloatFormat;
use cagerig::{Skeleton, TriMesh};
use cagerig_formats::{
    FormatError, ImportOptions, StaticMesh, import_character, import_static_mesh,
};
use serde::Serialize;

use crate::weights_progress::DelayedBar;

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Mesh to bind: OBJ, or a glTF 2.0 (`.glb`/`.gltf`) or FBX file: a character (its rest
    /// pose; its own weights are ignored) or a mesh with no skin (every mesh of the file in
    /// world space, as `cagerig_formats::import_static_mesh` reads it).
    pub mesh: PathBuf,
    /// Skeleton (`.skt`, rest pose in the mesh's space). Required for an OBJ and for a glTF/FBX
    /// file with no skin; a glTF/FBX character defaults to its own skeleton.
    #[arg(long)]
    pub skeleton: Option<PathBuf>,
    /// A closed cage (OBJ) around the mesh: its interior is part of the volume the weights are
    /// computed in (it bounds the volume of a mesh with large holes).
    #[arg(long)]
    pub cage: Option<PathBuf>,
    /// glTF/FBX: the skin whose skeleton to bind to, by name or index (default: the first).
    #[arg(long)]
    pub skin: Option<String>,
    /// Most joints influencing one vertex.
    #[arg(long, default_value_t = DEFAULT_MAX_INFLUENCES)]
    pub max_influences: usize,
    /// Voxels along the longest side of the mesh's box (finer separates closer limbs).
    #[arg(long, default_value_t = DEFAULT_RESOLUTION)]
    pub resolution: usize,
    /// Falloff exponent p of w ∝ (d_min / d)^p: larger gives sharper joints.
    #[arg(long, default_value_t = DEFAULT_EXPONENT)]
    pub exponent: f64,
    /// Which tip joints (joints with no child) deform: `auto` (all but names ending in end,
    /// nub, tip or null), `all`, `none`, or a comma-separated list of tip joint names.
    #[arg(long, default_value = "auto")]
    pub tips: String,
    /// Write the weights here (`.skw`: `<joint> <vertex> <weight>` lines, cagerig's vertex
    /// order and joint indices; replaced atomically).
    #[arg(long)]
    pub out: PathBuf,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct WeightsOutput<'a> {
    mesh: String,
    vertices: usize,
    triangles: usize,
    joints: usize,
    deforming_joints: Vec<&'a str>,
    static_joints: Vec<&'a str>,
    max_influences: usize,
    /// `influences_histogram[k]`: vertices with k influences.
    influences_histogram: Vec<usize>,
    voxel_grid: [usize; 3],
    voxel_size: f64,
    solid_voxels: usize,
    capped_holes: usize,
    straight_distance_vertices: usize,
    warnings: Vec<String>,
    seconds: f64,
    out: &'a PathBuf,
}

/// The mesh, the skeleton and the import's notes.
fn load(args: &Args) -> anyhow::Result<(TriMesh, Skeleton, Vec<String>)> {
    if crate::interchange::is_interchange(&args.mesh)? {
        let options = ImportOptions {
            skin: args.skin.clone(),
            ..ImportOptions::default()
        };
        return match import_character(&args.mesh, &options) {
            Ok(character) => {
                let skeleton = match &args.skeleton {
                    Some(p) => read_skt(p).with_context(|| format!("reading {}", p.display()))?,
                    None => character.skeleton,
                };
                Ok((character.mesh, skeleton, Vec::new()))
            }
            // A static mesh (a sculpt, a scan): every mesh of the file, bound to --skeleton.
            Err(FormatError::NoSkin { path, format }) => {
                let Some(p) = &args.skeleton else {
                    bail!(
                        "{}: the {format} file has no skin, so it has no skeleton of its own: --skeleton FILE.skt is required for a file with no skin (lines `j <index> <name> <parent index or -1> x y z` in the file's world space)",
                        path.display()
                    );
                };
                let skeleton = read_skt(p).with_context(|| format!("reading {}", p.display()))?;
                let StaticMesh { mesh, warnings, .. } = import_static_mesh(&args.mesh)?;
                Ok((
                    mesh,
                    skeleton,
                    warnings.iter().map(ToString::to_string).collect(),
                ))
            }
            Err(e) => Err(e.into()),
        };
    }
    if args.skin.is_some() {
        bail!(
            "--skin names a skin of a glTF/FBX file; {} is an OBJ",
            args.mesh.display()
        );
    }
    let mesh = read_obj(&args.mesh).with_context(|| format!("reading {}", args.mesh.display()))?;
    let Some(p) = &args.skeleton else {
        bail!(
            "{} is an OBJ: give its skeleton with --skeleton FILE.skt (lines `j <index> <name> \
             <parent index or -1> x y z`, see the README)",
            args.mesh.display()
        );
    };
    let skeleton = read_skt(p).with_context(|| format!("reading {}", p.display()))?;
    Ok((mesh, skeleton, Vec::new()))
}

/// The `--tips` value as a policy, tip names resolved against `skeleton`.
fn tips(value: &str, skeleton: &Skeleton) -> anyhow::Result<TipJoints> {
    Ok(match value {
        "auto" => TipJoints::AllButEndMarkers,
        "all" => TipJoints::All,
        "none" => TipJoints::None,
        list => TipJoints::Only(
            list.split(',')
                .map(|name| {
                    let name = name.trim();
                    skeleton.find(name).with_context(|| {
                        format!(
                            "--tips: expected auto, all, none or tip joint names; found {name:?}, \
                             which is not a joint of the skeleton ({} joints)",
                            skeleton.len()
                        )
                    })
                })
                .collect::<anyhow::Result<Vec<usize>>>()?,
        ),
    })
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (mesh, skeleton, import_notes) = load(args)?;
    let cage = match &args.cage {
        Some(p) => Some(read_obj(p).with_context(|| format!("reading the cage {}", p.display()))?),
        None => None,
    };
    let options = AutoWeightsOptions {
        max_influences: args.max_influences,
        resolution: args.resolution,
        exponent: args.exponent,
        tips: tips(&args.tips, &skeleton)?,
        ..AutoWeightsOptions::default()
    };
    let name = args.mesh.display().to_string();
    let start = Instant::now();
    let bar = DelayedBar::new();
    let result = AutoWeights::new(options)?
        .compute_with_progress(&mesh, &skeleton, cage.as_ref(), &|p| bar.update(p))
        .with_context(|| format!("computing automatic weights for {name}"))?;
    bar.finish();
    let seconds = start.elapsed().as_secs_f64();
    write_skw(
        &args.out,
        &result.weights,
        &skeleton,
        FloatFormat::RoundTrip,
    )
    .context("writing the weights")?;
    let w = &result.weights;
    let mut histogram = vec![0usize; w.max_influences() + 1];
    for v in 0..w.num_vertices() {
        histogram[w.row(v).0.len()] += 1;
    }
    let AutoWeightsReport {
        dims,
        spacing,
        solid_voxels,
        capped_holes,
        deforming_joints,
        straight_distance_vertices,
        warnings,
    } = &result.report;
    let joint_name = |j: usize| skeleton.joint(j).name.as_str();
    let output = WeightsOutput {
        mesh: name,
        vertices: mesh.num_vertices(),
        triangles: mesh.num_triangles(),
        joints: skeleton.len(),
        deforming_joints: deforming_joints.iter().map(|&j| joint_name(j)).collect(),
        static_joints: (0..skeleton.len())
            .filter(|j| !deforming_joints.contains(j))
            .map(joint_name)
            .collect(),
        max_influences: w.max_influences(),
        influences_histogram: histogram,
        voxel_grid: *dims,
        voxel_size: *spacing,
        solid_voxels: *solid_voxels,
        capped_holes: *capped_holes,
        straight_distance_vertices: *straight_distance_vertices,
        warnings: import_notes
            .into_iter()
            .chain(warnings.iter().map(ToString::to_string))
            .collect(),
        seconds,
        out: &args.out,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&output)?);
    } else {
        print_report(&output);
    }
    Ok(())
}

fn print_report(o: &WeightsOutput) {
    println!(
        "mesh           {} ({} vertices, {} triangles)",
        o.mesh, o.vertices, o.triangles
    );
    println!(
        "skeleton       {} joints, {} deforming",
        o.joints,
        o.deforming_joints.len()
    );
    if !o.static_joints.is_empty() {
        println!("no weight      {}", o.static_joints.join(", "));
    }
    println!(
        "voxels         {}×{}×{} grid, voxel size {:.4}, {} solid ({} holes capped)",
        o.voxel_grid[0],
        o.voxel_grid[1],
        o.voxel_grid[2],
        o.voxel_size,
        o.solid_voxels,
        o.capped_holes
    );
    println!(
        "{}",
        crate::interchange::influences_line(o.max_influences, &o.influences_histogram)
    );
    for w in &o.warnings {
        println!("warning        {w}");
    }
    println!("time           {:.3} s", o.seconds);
    println!("written        {}", o.out.display());
}

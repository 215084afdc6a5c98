//! `cagerig`: command-line front end of the cagerig library.

mod animate;
mod bench;
mod bench_bandwidth;
mod bench_table;
mod cage;
mod commands;
mod edit;
mod errors;
mod export;
mod interchange;
mod output_dir;
mod pictures;
mod render;
mod rig_source;
mod state_files;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use rig_source::RigArgs;

#[derive(Parser)]
#[command(
    name = "cagerig",
    version,
    about = "Real-time deformation with coupled cages and skeletons"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Counts, discovered files and validation warnings of a rig.
    Info {
        #[command(flatten)]
        rig: RigArgs,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Compute mean value coordinates Φ of the mesh w.r.t. the cage, in the cage-weights format.
    Coords {
        #[command(flatten)]
        rig: RigArgs,
        /// Output file (`<cageVertex> <meshVertex> <weight>` lines).
        #[arg(long)]
        out: PathBuf,
        /// Write 6 fixed decimals like the paper tool instead of round-trip floats.
        #[arg(long)]
        fixed6: bool,
    },
    /// Select the MaxVol rows of Φ and print log|det|.
    Maxvol {
        #[command(flatten)]
        rig: RigArgs,
        /// Output `.maxvol` file.
        #[arg(long)]
        out: PathBuf,
        /// Machine-readable output (errors too).
        #[arg(long)]
        json: bool,
    },
    /// Replay an edit script (JSON) and write every structure after each step.
    #[command(after_long_help = edit::SCRIPT_HELP)]
    Edit {
        #[command(flatten)]
        rig: RigArgs,
        #[command(flatten)]
        auto_cage: rig_source::AutoCageArgs,
        /// The script: {"skinning":..., "steps":[{"op":...}, ...]} (operations: see --help).
        #[arg(long)]
        script: PathBuf,
        /// Output folder; it appears complete, only after every step succeeded.
        #[arg(long)]
        out: PathBuf,
        /// Replace a non-empty --out that holds an earlier run's state files.
        #[arg(long)]
        force: bool,
        /// Also write a picture of each state (rest pose left, current pose right) as PNG;
        /// needs a Vulkan or GL adapter (software ones work).
        #[arg(long)]
        render: bool,
        /// Skinning method (overrides the script's).
        #[arg(long, value_enum)]
        skinning: Option<commands::SkinningArg>,
        #[command(flatten)]
        session: commands::SessionArgs,
    },
    /// Sample skeleton and cage animations at given times and write the structures.
    Animate {
        #[command(flatten)]
        rig: RigArgs,
        #[command(flatten)]
        auto_cage: rig_source::AutoCageArgs,
        /// Skeleton animation (V1/V2/V3 text format).
        #[arg(long)]
        skeleton_anim: Option<PathBuf>,
        /// Cage animation (rest-cage offsets).
        #[arg(long)]
        cage_anim: Option<PathBuf>,
        /// glTF/FBX: the file's animation to play, by name or index (all channels).
        #[arg(long)]
        animation: Option<String>,
        /// Comma-separated sample times in seconds, each once (negative times allowed).
        #[arg(
            long,
            value_delimiter = ',',
            required = true,
            allow_hyphen_values = true
        )]
        times: Vec<f64>,
        /// Output folder; it appears complete, only after every sample succeeded.
        #[arg(long)]
        out: PathBuf,
        /// Replace a non-empty --out that holds an earlier run's state files.
        #[arg(long)]
        force: bool,
        /// Also write a picture of each state (rest pose left, current pose right) as PNG;
        /// needs a Vulkan or GL adapter (software ones work).
        #[arg(long)]
        render: bool,
        /// Skinning method.
        #[arg(long, value_enum)]
        skinning: Option<commands::SkinningArg>,
        #[command(flatten)]
        session: commands::SessionArgs,
    },
    /// A hybrid edit on a built-in rig: bend with the skeleton, inflate with the cage, grab the
    /// current cage; writes the results and prints each sync's time.
    Demo {
        /// Built-in rig to use.
        #[arg(long, default_value = "bar")]
        builtin: String,
        /// Mesh resolution parameter of the built-in rig.
        #[arg(long)]
        resolution: Option<usize>,
        /// Output directory.
        #[arg(long, default_value = "cagerig-demo")]
        out: PathBuf,
        /// Do not render the PNG picture of each step (rest and current pose side by side).
        #[arg(long)]
        no_pictures: bool,
    },
    /// Midpoint-subdivide a rig N times and write its files (mesh, .skt, .skw, cage, Φ, MaxVol).
    Subdivide {
        #[command(flatten)]
        rig: RigArgs,
        /// Rounds of midpoint subdivision (each multiplies the triangles by 4).
        #[arg(long, default_value_t = 1)]
        levels: usize,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Base name of the written files (no path separator).
        #[arg(long, default_value = "rig")]
        name: String,
    },
    /// Per-operator timings in the layout of the paper's Table 1.
    Bench(bench::BenchArgs),
    /// Render the rig (rest and/or current pose, cage, skeleton, colour maps) to PNG, after an
    /// edit script or at animation times; needs a Vulkan or GL adapter (software ones work).
    Render(Box<render::RenderArgs>),
    /// Export the (edited) character as a rigged glTF binary (.glb).
    Export(export::ExportArgs),
    /// Generate a validated deformation cage for a mesh.
    Cage(cage::CageArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let json = match &cli.command {
        Command::Info { json, .. } | Command::Maxvol { json, .. } => *json,
        Command::Bench(args) => args.json,
        _ => false,
    };
    let result = match cli.command {
        Command::Info { rig, json } => match &rig.mesh {
            Some(m) if interchange::is_interchange(m) => {
                interchange::info(m, rig.skin.as_deref(), json)
            }
            _ => commands::info(&rig, json),
        },
        Command::Coords { rig, out, fixed6 } => commands::coords(&rig, &out, fixed6),
        Command::Maxvol { rig, out, json } => commands::maxvol(&rig, &out, json),
        Command::Edit {
            rig,
            auto_cage,
            script,
            out,
            force,
            render,
            skinning,
            session,
        } => edit::edit(
            &rig, &auto_cage, &script, &out, force, render, skinning, &session,
        ),
        Command::Animate {
            rig,
            auto_cage,
            skeleton_anim,
            cage_anim,
            animation,
            times,
            out,
            force,
            render,
            skinning,
            session,
        } => animate::animate(
            &rig,
            &auto_cage,
            skeleton_anim.as_deref(),
            cage_anim.as_deref(),
            animation.as_deref(),
            &times,
            &out,
            force,
            render,
            skinning,
            &session,
        ),
        Command::Demo {
            builtin,
            resolution,
            out,
            no_pictures,
        } => commands::demo(&builtin, resolution, &out, !no_pictures),
        Command::Subdivide {
            rig,
            levels,
            out,
            name,
        } => commands::subdivide(&rig, levels, &out, &name),
        Command::Bench(args) => bench::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Cage(args) => cage::run(&args),
    };
    errors::exit(result, json)
}

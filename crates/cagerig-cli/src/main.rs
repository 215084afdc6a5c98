//! `cagerig`: command-line front end of the cagerig library.

mod animation_args;
mod bench_bandwidth;
mod bench_events;
mod bench_green;
mod bench_report;
mod bench_table;
mod commands;
mod errors;
mod interchange;
mod output_dir;
mod pictures;
mod rig_source;
mod session_args;
mod state_files;
mod weights_progress;

use clap::{Parser, Subcommand};

use commands::{
    animate, bench, cage, coords, demo, edit, export, info, maxvol, render, subdivide, weights,
};

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
    Info(info::Args),
    /// Compute mean value coordinates Φ of the mesh w.r.t. the cage, in the cage-weights format.
    Coords(coords::Args),
    /// Select the MaxVol rows of Φ and print log|det|.
    Maxvol(maxvol::Args),
    /// Replay an edit script (JSON) and write every structure after each step.
    #[command(after_long_help = edit::SCRIPT_HELP)]
    Edit(edit::Args),
    /// Sample skeleton and cage animations at given times and write the structures.
    Animate(animate::Args),
    /// A hybrid edit on a built-in rig: bend with the skeleton, inflate with the cage, grab the
    /// current cage; writes the results and prints each sync's time.
    Demo(demo::Args),
    /// Midpoint-subdivide a rig N times and write its files (mesh, .skt, .skw, cage, Φ, MaxVol).
    Subdivide(subdivide::Args),
    /// Per-operator timings in the layout of the paper's Table 1.
    Bench(bench::Args),
    /// Render the rig (rest and/or current pose, cage, skeleton, colour maps) to PNG, after an
    /// edit script or at animation times; needs a Vulkan or GL adapter (software ones work).
    Render(Box<render::Args>),
    /// Export the (edited) character as a rigged glTF binary (.glb).
    Export(export::Args),
    /// Generate a validated deformation cage for a mesh.
    Cage(cage::Args),
    /// Compute skinning weights for a mesh and a skeleton (geodesic voxel binding), as `.skw`.
    Weights(weights::Args),
}

impl Command {
    /// Whether the user asked for machine-readable output (then errors are JSON too).
    fn json(&self) -> bool {
        match self {
            Command::Info(args) => args.json,
            Command::Maxvol(args) => args.json,
            Command::Bench(args) => args.json,
            Command::Cage(args) => args.json,
            Command::Weights(args) => args.json,
            Command::Coords(_)
            | Command::Edit(_)
            | Command::Animate(_)
            | Command::Demo(_)
            | Command::Subdivide(_)
            | Command::Render(_)
            | Command::Export(_) => false,
        }
    }

    fn run(&self) -> anyhow::Result<()> {
        match self {
            Command::Info(args) => info::run(args),
            Command::Coords(args) => coords::run(args),
            Command::Maxvol(args) => maxvol::run(args),
            Command::Edit(args) => edit::run(args),
            Command::Animate(args) => animate::run(args),
            Command::Demo(args) => demo::run(args),
            Command::Subdivide(args) => subdivide::run(args),
            Command::Bench(args) => bench::run(args),
            Command::Render(args) => render::run(args),
            Command::Export(args) => export::run(args),
            Command::Cage(args) => cage::run(args),
            Command::Weights(args) => weights::run(args),
        }
    }
}

/// A closed pipe on stdout (`cagerig bench | head`) ends the process quietly, as for other
/// command-line tools, instead of a panic in `println!` (Rust ignores SIGPIPE by default).
#[cfg(unix)]
#[expect(
    unsafe_code,
    reason = "libc::signal, the one way to restore SIGPIPE's default"
)]
fn quiet_on_closed_pipe() {
    // SAFETY: `signal` has no memory-safety preconditions; it runs first in `main`, before any
    // thread exists, and SIG_DFL installs no handler code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> std::process::ExitCode {
    #[cfg(unix)]
    quiet_on_closed_pipe();
    let cli = Cli::parse();
    let json = cli.command.json();
    errors::exit(cli.command.run(), json)
}

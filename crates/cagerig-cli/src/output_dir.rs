//! Output folders that are complete or absent (`edit`, `animate`, `demo`, `subdivide` and
//! `render --times/--turntable`): the staging policy is the library's
//! [`cagerig::io::staged_dir`], shared with the editor's export and Python; this module holds
//! the CLI's options and how its messages name the folder (`--out`, `--force`).

use std::path::PathBuf;

pub use cagerig::io::staged_dir::{FolderNaming, StagedDir};

/// How the CLI's messages name an output folder and the option that replaces it.
pub const OUT: FolderNaming = FolderNaming {
    folder: "--out",
    replace_option: Some("--force"),
};

/// `--out`, `--force`, `--render`: the output folder of a command that writes the rig's state
/// after each step or sample (`edit`, `animate`).
#[derive(Debug, Clone, clap::Args)]
pub struct StateOutputArgs {
    /// Output folder; it appears complete, only after every state was written.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a non-empty --out that holds an earlier run's output.
    #[arg(long)]
    pub force: bool,
    /// Also write a picture of each state (rest pose left, current pose right) as PNG;
    /// needs a Vulkan or GL adapter (software ones work).
    #[arg(long)]
    pub render: bool,
}

//! The subcommands, one file each: an `Args` struct (its options, parsed by clap) and
//! `run(&Args)`. A new subcommand is a new file here, a variant of `Command` in `main.rs` and its
//! arms in `Command::run` and `Command::json`.

pub mod animate;
pub mod bench;
pub mod cage;
pub mod coords;
pub mod demo;
pub mod edit;
pub mod export;
pub mod info;
pub mod maxvol;
pub mod render;
pub mod subdivide;
pub mod weights;

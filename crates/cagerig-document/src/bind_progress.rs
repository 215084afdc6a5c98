//! How far a bind is, as the bind reports it and an offloaded computation of its automatic
//! weights answers it ([`crate::binding`], [`crate::offload`]).

use cagerig::auto_weights::Progress;
use cagerig::session::BindStage;

/// How far a bind is: the automatic weights' stages (when it computes them), then the rig's
/// binding ([`cagerig::session::RigSession::with_progress`]).
#[derive(Debug, Clone, Copy)]
pub enum BindStep {
    /// The automatic weights.
    Weights(Progress),
    /// The rig's binding: its `stage`, `done` of `total`.
    Rig {
        stage: BindStage,
        done: usize,
        total: usize,
    },
}

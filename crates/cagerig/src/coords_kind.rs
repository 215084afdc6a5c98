//! The kind of cage coordinates a rig binds with, as a value: its names, and the one parser of
//! them (`--coords`, Python's `coords=`, session files).
//!
//! - [`CoordsKind::Mvc`]: mean value coordinates Φ, the paper's linear map M = ΦC.
//! - [`CoordsKind::Green`]: Green coordinates (Lipman et al. 2008), M = φC + ψ·(s(C)·N(C)):
//!   quasi-conformal, shape-preserving cage edits; the sync operators become Newton iterations
//!   (see `docs/green-coordinates.md`).

/// The cage coordinates of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum CoordsKind {
    /// Mean value coordinates (Eq. 7, linear in C).
    #[default]
    Mvc,
    /// Green coordinates (vertex and face terms, non-linear in C).
    Green,
}

/// A coordinates name that [`CoordsKind::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown cage coordinates {found:?}: expected {}",
    CoordsKind::names_text()
)]
pub struct UnknownCoordsKind {
    /// The name as given.
    pub found: String,
}

impl CoordsKind {
    /// Every kind, in the order front ends list them.
    pub const ALL: [CoordsKind; 2] = [Self::Mvc, Self::Green];

    /// The name in options, scripts and files: `"mvc"` or `"green"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Mvc => "mvc",
            Self::Green => "green",
        }
    }

    /// The name for people: `"mean value"` or `"Green"`.
    pub const fn label(self) -> &'static str {
        match self {
            Self::Mvc => "mean value",
            Self::Green => "Green",
        }
    }

    /// Whether the rest skin is linear in the rest cage (M = ΦC).
    pub const fn is_linear(self) -> bool {
        match self {
            Self::Mvc => true,
            Self::Green => false,
        }
    }
}

crate::named_kind::named_kind!(CoordsKind, UnknownCoordsKind);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_back_and_unknown_names_list_the_accepted_ones() {
        for k in CoordsKind::ALL {
            assert_eq!(k.name().parse::<CoordsKind>(), Ok(k));
            assert_eq!(k.to_string(), k.name());
            let json = serde_json::to_string(&k).unwrap();
            assert_eq!(serde_json::from_str::<CoordsKind>(&json).unwrap(), k);
        }
        assert_eq!("GREEN".parse::<CoordsKind>(), Ok(CoordsKind::Green));
        assert_eq!(
            "harmonic".parse::<CoordsKind>().unwrap_err().to_string(),
            "unknown cage coordinates \"harmonic\": expected mvc or green"
        );
    }
}

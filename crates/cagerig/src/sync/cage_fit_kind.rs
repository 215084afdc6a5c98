//! How CageUp fits the current cage C' to the current skin M', as a value: its names, and the
//! one parser of them (`--cage-fit`, Python's `cage_fit=`, the studio, session files).
//!
//! - [`CageFitKind::Regularised`] (the default): C' matches the skin on the fitting rows where
//!   it can and stays close to the rest cage carried by the skeleton, P(C, S'), elsewhere
//!   (see [`super::cage_prior`] and `docs/method.md`). The handle stays on the body.
//! - [`CageFitKind::Paper`]: the paper's Eq. 8, C' = Φ̃⁻¹M̃' on the MaxVol rows (exact on those
//!   rows, unbounded between them), as the paper's own tool computes it.
//!
//! Both keep the paper's guarantees: CageRev lands a grab exactly, the loop
//! C' → C → S → S' → C' is a fixed point and M' does not depend on the choice.

/// The CageUp fit of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum CageFitKind {
    /// Least squares on the fitting rows plus λ‖L(C' − P)‖², P the skeleton-carried rest cage.
    #[default]
    Regularised,
    /// The paper's interpolation of the MaxVol rows (Eq. 8).
    Paper,
}

/// A cage-fit name that [`CageFitKind::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown cage fit {found:?}: expected {}", CageFitKind::names_text())]
pub struct UnknownCageFitKind {
    /// The name as given.
    pub found: String,
}

impl CageFitKind {
    /// Every kind, in the order front ends list them.
    pub const ALL: [CageFitKind; 2] = [Self::Regularised, Self::Paper];

    /// The name in options, scripts and files: `"regularised"` or `"paper"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Regularised => "regularised",
            Self::Paper => "paper",
        }
    }

    /// The name for people.
    pub const fn label(self) -> &'static str {
        match self {
            Self::Regularised => "regularised (follows the skeleton)",
            Self::Paper => "paper (exact on the MaxVol rows)",
        }
    }

    /// One line of help for option lists.
    pub const fn help(self) -> &'static str {
        match self {
            Self::Regularised => {
                "C' fits the skin and stays near the rest cage carried by the skeleton \
                 (the default)"
            }
            Self::Paper => "the paper's Eq. 8: C' interpolates the skin at the MaxVol rows",
        }
    }
}

crate::named_kind::named_kind!(CageFitKind, UnknownCageFitKind, CageFitKind::help);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_back_and_unknown_names_list_the_accepted_ones() {
        for k in CageFitKind::ALL {
            assert_eq!(k.name().parse::<CageFitKind>(), Ok(k));
            assert_eq!(k.to_string(), k.name());
            let json = serde_json::to_string(&k).unwrap();
            assert_eq!(serde_json::from_str::<CageFitKind>(&json).unwrap(), k);
        }
        assert_eq!("PAPER".parse::<CageFitKind>(), Ok(CageFitKind::Paper));
        assert_eq!(
            "exact".parse::<CageFitKind>().unwrap_err().to_string(),
            "unknown cage fit \"exact\": expected regularised or paper"
        );
    }
}

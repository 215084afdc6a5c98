//! How a generated cage is laid out around a rigged character ([`CageLayout`]).

/// How cage generation shapes the cage of a character that has a skeleton.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum CageLayout {
    /// Limbs kept apart where the skin's dominant joints differ
    /// ([`super::limb_separation`]) and rings of cage vertices around the articulations
    /// ([`super::skeleton_guide`]); without a skeleton, the offset layout.
    #[default]
    Skeleton,
    /// One offset surface around the whole skin, simplified in quadric order: close limbs
    /// share one shell.
    Offset,
}

/// A cage-layout name that [`CageLayout::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown cage layout {found:?}: expected {}", CageLayout::names_text())]
pub struct UnknownCageLayout {
    /// The name as given.
    pub found: String,
}

impl CageLayout {
    /// Every kind, in the order front ends list them.
    pub const ALL: [CageLayout; 2] = [Self::Skeleton, Self::Offset];

    /// The name in options, scripts and files: `"skeleton"` or `"offset"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Skeleton => "skeleton",
            Self::Offset => "offset",
        }
    }

    /// One line of help for option lists.
    pub const fn help(self) -> &'static str {
        match self {
            Self::Skeleton => {
                "limbs kept apart by the skin's dominant joints, rings of vertices at the \
                 articulations (the default; needs a skeleton)"
            }
            Self::Offset => "one offset surface around the whole skin: close limbs share a shell",
        }
    }
}

crate::named_kind::named_kind!(CageLayout, UnknownCageLayout, CageLayout::help);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_unknown_names_are_named() {
        for kind in CageLayout::ALL {
            assert_eq!(kind.name().parse::<CageLayout>(), Ok(kind));
        }
        assert_eq!("Offset".parse::<CageLayout>(), Ok(CageLayout::Offset));
        let err = "bones".parse::<CageLayout>().unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown cage layout \"bones\": expected skeleton or offset"
        );
    }
}

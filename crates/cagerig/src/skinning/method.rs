//! The skinning method S→S'→M' as a value: its names, and the one parser of them.
//!
//! Every front end (CLI options, edit scripts, Python keywords, the studio) names a method through
//! [`SkinningMethod::name`] and reads one through [`std::str::FromStr`]; adding a method means a
//! new variant here and the kernels in [`crate::session`]'s skinning dispatch, and nothing else
//! (the compiler points at every exhaustive `match`).

/// The skinning method S→S'→M' of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum SkinningMethod {
    /// Linear blend skinning (Eq. 2–3).
    #[default]
    Lbs,
    /// Dual quaternion skinning (Eq. 4).
    Dqs,
    /// Optimised centres of rotation (Eq. 5–6).
    Cor,
    /// Per-vertex blend of LBS and DQS, `v' = (1 − b_v)·LBS(v) + b_v·DQS(v)` with the rig's DQ
    /// blend weights `b` (`#V`, in [0, 1]): Maya's "weight blended" skin cluster (ufbx's
    /// `UFBX_SKINNING_METHOD_BLENDED_DQ_LINEAR`). Needs [`super::DqBlendWeights`] in the rig.
    Blended,
    /// The method passed in from outside the library
    /// (`crate::session::SessionOptions::external_skinning`, a
    /// `crate::session::SkinningBackend`). It has no name front ends choose: it is not in
    /// [`SkinningMethod::ALL`], and a session built without one refuses it.
    External,
}

/// A method name that [`SkinningMethod::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown skinning method {found:?}: expected {}",
    SkinningMethod::names_text()
)]
pub struct UnknownSkinningMethod {
    /// The name as given.
    pub found: String,
}

impl SkinningMethod {
    /// Every method front ends name, in the order they list them ([`SkinningMethod::External`]
    /// is passed in as a value, not named).
    pub const ALL: [SkinningMethod; 4] = [Self::Lbs, Self::Dqs, Self::Cor, Self::Blended];

    /// The method a rig opens with, by the one rule of every front end: the one the user chose
    /// (`--skinning`, a script's `"skinning"`, Python's `skinning=`), else the one the
    /// character's file says its authoring tool uses (FBX skin deformers), else LBS.
    pub fn chosen_else_file(chosen: Option<Self>, file: Option<Self>) -> Self {
        chosen.or(file).unwrap_or_default()
    }

    /// The name in scripts, options and files: `"lbs"`, `"dqs"`, `"cor"` or `"blended"`
    /// (`"external"` for the method passed in: saved states and edit scripts, read through serde,
    /// take it back, and a session without such a method refuses it; the options front ends
    /// list, read through `FromStr`, do not offer it).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Lbs => "lbs",
            Self::Dqs => "dqs",
            Self::Cor => "cor",
            Self::Blended => "blended",
            Self::External => "external",
        }
    }

    /// Whether M' is linear in the skinning transforms (LBS): CageUp then fits the skinned rows
    /// directly; the other methods, an external one included, fit their ghost LBS (see
    /// `CageFitSource`). The session's one rule of what CageUp fits.
    pub const fn is_linear(self) -> bool {
        match self {
            Self::Lbs => true,
            Self::Dqs | Self::Cor | Self::Blended | Self::External => false,
        }
    }

    /// The name for people (menus, status lines): `"LBS"`, `"DQS"`, `"CoR"` or
    /// `"LBS/DQS blend"`.
    pub const fn label(self) -> &'static str {
        match self {
            Self::Lbs => "LBS",
            Self::Dqs => "DQS",
            Self::Cor => "CoR",
            Self::Blended => "LBS/DQS blend",
            Self::External => "external method",
        }
    }

    /// Whether the method reads per-vertex data the rig may lack: the DQ blend weights of
    /// [`SkinningMethod::Blended`] (a session refuses the method without them).
    pub const fn needs_dq_blend_weights(self) -> bool {
        match self {
            Self::Lbs | Self::Dqs | Self::Cor | Self::External => false,
            Self::Blended => true,
        }
    }
}

crate::named_kind::named_kind!(
    SkinningMethod,
    UnknownSkinningMethod,
    |_method: SkinningMethod| "",
    no_serde
);

impl serde::Serialize for SkinningMethod {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for SkinningMethod {
    /// A name of [`SkinningMethod::ALL`] through `FromStr`, or `"external"`: a saved state (or an
    /// edit script) of a session whose method was passed in reads back as
    /// [`SkinningMethod::External`], and a session without such a method refuses it
    /// ([`crate::RigError::NoExternalSkinning`]).
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let text = <String as serde::Deserialize>::deserialize(deserializer)?;
        if crate::named_kind::same_name(Self::External.name(), &text) {
            return Ok(Self::External);
        }
        text.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_back_to_its_method() {
        for m in SkinningMethod::ALL {
            assert_eq!(m.name().parse::<SkinningMethod>(), Ok(m));
            if m != SkinningMethod::Blended {
                // "LBS/DQS blend" is a label, not a name.
                assert_eq!(m.label().parse::<SkinningMethod>(), Ok(m));
            }
            assert_eq!(m.to_string(), m.name());
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(json, format!("\"{}\"", m.name()));
            assert_eq!(serde_json::from_str::<SkinningMethod>(&json).unwrap(), m);
        }
    }

    #[test]
    fn unknown_names_list_the_accepted_ones() {
        let err = "quaternions".parse::<SkinningMethod>().unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown skinning method \"quaternions\": expected lbs, dqs, cor or blended"
        );
        let err = serde_json::from_str::<SkinningMethod>("\"lbx\"").unwrap_err();
        assert!(
            err.to_string()
                .contains("expected lbs, dqs, cor or blended"),
            "{err}"
        );
    }

    #[test]
    fn the_external_method_is_not_a_name_front_ends_choose() {
        assert!(!SkinningMethod::ALL.contains(&SkinningMethod::External));
        // Saved states read the method passed in back; the options' parser does not name it.
        let json = serde_json::to_string(&SkinningMethod::External).unwrap();
        assert_eq!(json, "\"external\"");
        assert_eq!(
            serde_json::from_str::<SkinningMethod>(&json).unwrap(),
            SkinningMethod::External
        );
        assert!("external".parse::<SkinningMethod>().is_err());
        assert!("external".parse::<SkinningMethod>().is_err());
        assert!(!SkinningMethod::External.is_linear());
    }
}

//! The text form of the kinds front ends choose by name ([`crate::SkinningMethod`],
//! [`crate::CoordsKind`]): one parser and one printer, generated from the kind's `ALL` and
//! `name`, so that the CLI, Python, scripts and session files all read and write the same names.

/// For a kind with `const ALL: [Self; N]` and `const fn name(self) -> &'static str`, and an
/// error type with a `found: String` field: `FromStr` (a name of `ALL`, ignoring ASCII case,
/// else the error naming what was found), `Display` (the name), and serde as the name (read
/// back through `FromStr`).
macro_rules! named_kind {
    ($kind:ident, $error:ident) => {
        impl ::std::str::FromStr for $kind {
            type Err = $error;

            /// The kind whose `name()` is `text`, ignoring ASCII case.
            fn from_str(text: &str) -> Result<Self, Self::Err> {
                Self::ALL
                    .into_iter()
                    .find(|k| k.name().eq_ignore_ascii_case(text))
                    .ok_or_else(|| $error {
                        found: text.to_string(),
                    })
            }
        }

        impl ::std::fmt::Display for $kind {
            /// Writes `name()`.
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::serde::Serialize for $kind {
            fn serialize<S: ::serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                serializer.serialize_str(self.name())
            }
        }

        impl<'de> ::serde::Deserialize<'de> for $kind {
            /// Reads a name through `FromStr`, the one parser of these names.
            fn deserialize<D: ::serde::Deserializer<'de>>(
                deserializer: D,
            ) -> Result<Self, D::Error> {
                let text = <String as ::serde::Deserialize>::deserialize(deserializer)?;
                text.parse().map_err(::serde::de::Error::custom)
            }
        }
    };
}

pub(crate) use named_kind;

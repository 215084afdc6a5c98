//! The text form of the kinds front ends choose by name ([`crate::SkinningMethod`],
//! [`crate::CoordsKind`], [`crate::CageFitKind`], [`crate::session::UnfittedCagePolicy`]): one
//! parser and one printer, generated from the kind's `ALL`, `name` and `help`, so that the CLI's
//! values and `--help`, Python's strings and stubs, scripts and session files all read and write
//! the same names ([`NamedKind`]).

/// A kind front ends choose by name. Implemented by [`named_kind!`] from the kind's own
/// `ALL`, `name` (and `help`), so that generic front-end code (the CLI's value parser, the
/// Python package's list of names) has one definition per kind.
pub trait NamedKind: Copy + std::str::FromStr + std::fmt::Display + 'static {
    /// Every kind, in the order front ends list them.
    const ALL: &'static [Self];
    /// The kind's name: the CLI value, the Python string, the session files' value.
    fn name(self) -> &'static str;
    /// One line saying what the kind does (empty when the name says it).
    fn help(self) -> &'static str;
    /// The accepted names as a sentence: `"lbs, dqs, cor or blended"`.
    fn names_text() -> String {
        let names: Vec<&str> = Self::ALL.iter().map(|k| k.name()).collect();
        crate::error::names_sentence(&names)
    }
}

/// For a kind with `const ALL: [Self; N]` and `const fn name(self) -> &'static str`, and an
/// error type with a `found: String` field: `FromStr` (a name of `ALL`, ignoring ASCII case,
/// else the error naming what was found), `Display` (the name), and serde as the name (read
/// back through `FromStr`).
macro_rules! named_kind {
    ($kind:ident, $error:ident) => {
        $crate::named_kind::named_kind!($kind, $error, |_kind: $kind| "");
    };
    ($kind:ident, $error:ident, $help:expr) => {
        impl $crate::named_kind::NamedKind for $kind {
            const ALL: &'static [Self] = &$kind::ALL;
            fn name(self) -> &'static str {
                $kind::name(self)
            }
            fn help(self) -> &'static str {
                ($help)(self)
            }
        }

        impl $kind {
            /// The accepted names as a sentence (`"a, b or c"`).
            pub fn names_text() -> String {
                <Self as $crate::named_kind::NamedKind>::names_text()
            }
        }

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

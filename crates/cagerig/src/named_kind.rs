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
/// error type with a `found: String` field: [`NamedKind`], `FromStr` (a name of `ALL`, ignoring
/// ASCII case and reading `-` and `_` alike, else the error naming what was found), `Display`
/// (the name), and serde as the name (read back through `FromStr`). Forms:
/// `named_kind!(Kind, Error)`, `named_kind!(Kind, Error, Kind::help)` (a `fn(Kind) -> &str` for
/// `--help`), and `named_kind!(Kind, Error, Kind::help, no_serde)` for a kind that keeps serde of
/// its own.
macro_rules! named_kind {
    ($kind:ident, $error:ident) => {
        $crate::named_kind::named_kind!($kind, $error, |_kind: $kind| "");
    };
    ($kind:ident, $error:ident, $help:expr) => {
        $crate::named_kind::named_kind!($kind, $error, $help, no_serde);

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
    ($kind:ident, $error:ident, $help:expr, no_serde) => {
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

            /// The kind whose `name()` is `text`, ignoring ASCII case and reading `-` and `_`
            /// alike.
            fn from_str(text: &str) -> Result<Self, Self::Err> {
                Self::ALL
                    .into_iter()
                    .find(|k| $crate::named_kind::same_name(k.name(), text))
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
    };
}

/// Whether `text` is the kind name `name`, ignoring ASCII case and reading `-` and `_` alike
/// (`reference_tool` is `reference-tool`).
pub fn same_name(name: &str, text: &str) -> bool {
    let fold = |c: u8| match c {
        b'_' => b'-',
        c => c.to_ascii_lowercase(),
    };
    name.len() == text.len()
        && name
            .bytes()
            .zip(text.bytes())
            .all(|(a, b)| fold(a) == fold(b))
}

pub(crate) use named_kind;

#[cfg(test)]
mod tests {
    use super::same_name;

    #[test]
    fn names_match_ignoring_case_and_dash_or_underscore() {
        assert!(same_name("reference-tool", "Reference_Tool"));
        assert!(same_name("mvc", "MVC"));
        assert!(!same_name("mvc", "mv"));
        assert!(!same_name("reference-tool", "referencetool"));
    }
}

//! Names of fieldless enums (schemes, representations, conventions, world frames): the one place
//! a variant's name, the list of names, and the parsing of a name are written.
//!
//! [`named_enum!`](crate::named_enum) implements [`Named`] and [`std::str::FromStr`] for an enum
//! from one table of `Variant => "name"` rows, plus optional deprecated aliases (`"old" =>
//! Variant`) that parse but are not listed in [`Named::ALL`]. Bindings parse every enum through
//! `FromStr` and list names from `ALL`, so no name is written twice.

use crate::Error;

/// A fieldless enum with a canonical name per variant.
pub trait Named: Sized + Copy + PartialEq + std::str::FromStr<Err = Error> + 'static {
    /// Every variant, in declaration order.
    const ALL: &'static [Self];
    /// Deprecated names that still parse, with the variant each stands for.
    const ALIASES: &'static [(&'static str, Self)];
    /// The argument name used in parse errors (`"scheme"`, `"convention"`, …).
    const ARGUMENT: &'static str;

    /// The canonical name.
    fn name(self) -> &'static str;

    /// The canonical names of [`Named::ALL`], in order.
    fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|v| v.name()).collect()
    }

    /// The canonical name for `alias` when it is a deprecated alias, else `None`.
    fn canonical_of_alias(alias: &str) -> Option<&'static str> {
        Self::ALIASES.iter().find(|(a, _)| *a == alias).map(|(_, v)| v.name())
    }
}

/// Implements [`Named`], `FromStr`, `Display` and an inherent `name()` for a fieldless enum.
///
/// ```ignore
/// named_enum!(Scheme, "scheme", [Euler => "euler", Rk2 => "rk2"], aliases ["midpoint" => Rk2]);
/// ```
///
/// An unknown name is `Error::Parameter { name: "scheme", expected: "one of 'euler', 'rk2'",
/// got: "\"foo\"" }`.
#[macro_export]
macro_rules! named_enum {
    (
        $ty:ty, $argument:literal,
        [$first:ident => $first_name:literal $(, $variant:ident => $name:literal)* $(,)?]
        $(, aliases [$($alias:literal => $target:ident),* $(,)?])? $(,)?
    ) => {
        impl $ty {
            /// The canonical name (the one the bindings and the docs use).
            pub fn name(self) -> &'static str {
                match self {
                    Self::$first => $first_name,
                    $(Self::$variant => $name,)*
                }
            }
        }

        impl $crate::names::Named for $ty {
            const ALL: &'static [Self] = &[Self::$first $(, Self::$variant)*];
            const ALIASES: &'static [(&'static str, Self)] = &[$($(($alias, Self::$target)),*)?];
            const ARGUMENT: &'static str = $argument;

            fn name(self) -> &'static str {
                <$ty>::name(self)
            }
        }

        impl ::std::str::FromStr for $ty {
            type Err = $crate::Error;

            fn from_str(s: &str) -> $crate::Result<Self> {
                match s {
                    $first_name => Ok(Self::$first),
                    $($name => Ok(Self::$variant),)*
                    $($($alias => Ok(Self::$target),)*)?
                    _ => Err($crate::Error::Parameter {
                        name: $argument,
                        expected: concat!("one of '", $first_name, "'" $(, ", '", $name, "'")*),
                        got: format!("{s:?}"),
                    }),
                }
            }
        }

        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

/// Parses `value` as a `T`, attributing an unknown name to the argument `name` (for enums parsed
/// under another argument name than [`Named::ARGUMENT`]).
pub fn parse<T: Named>(name: &'static str, value: &str) -> crate::Result<T> {
    value.parse::<T>().map_err(|e| match e {
        Error::Parameter { expected, got, .. } => Error::Parameter { name, expected, got },
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::Named;
    use crate::Error;

    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Demo {
        One,
        Two,
    }
    crate::named_enum!(Demo, "demo", [One => "one", Two => "two"], aliases ["uno" => One]);

    #[test]
    fn names_parse_back_and_aliases_parse_but_are_not_listed() {
        for v in Demo::ALL {
            assert_eq!(v.name().parse::<Demo>(), Ok(*v));
        }
        assert_eq!(Demo::names(), ["one", "two"]);
        assert_eq!("uno".parse::<Demo>(), Ok(Demo::One));
        assert_eq!(Demo::canonical_of_alias("uno"), Some("one"));
        assert_eq!(Demo::canonical_of_alias("one"), None);
    }

    #[test]
    fn an_unknown_name_is_a_parameter_error_listing_the_canonical_names() {
        let e = "three".parse::<Demo>().err();
        assert_eq!(e.as_ref().and_then(Error::argument), Some("demo"));
        let text = e.map(|e| e.to_string());
        assert_eq!(text.as_deref(), Some("demo must be one of 'one', 'two', got \"three\""));
        let renamed = super::parse::<Demo>("other", "three");
        assert!(matches!(renamed, Err(Error::Parameter { name: "other", .. })));
    }
}

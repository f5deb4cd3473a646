//! Command-line knobs that take a value or `auto` (the value the dataset
//! asks for): `inlay train --sky`, `--refine-density-exponent`,
//! `--sparsity`.

use std::fmt::Display;
use std::str::FromStr;

/// A knob given as a value, or `auto`: chosen from the dataset once it is
/// read (each knob's own check holds the value's range).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Auto<T> {
    /// Chosen from the dataset.
    Auto,
    /// This value.
    Value(T),
}

impl<T: Copy> Auto<T> {
    /// The value given, or `auto` where none was.
    pub fn or(self, auto: T) -> T {
        match self {
            Auto::Auto => auto,
            Auto::Value(v) => v,
        }
    }

    /// Whether `auto` was given.
    pub fn is_auto(self) -> bool {
        matches!(self, Auto::Auto)
    }
}

/// Parses `auto` or a value of `T` (clap's `value_parser`), naming what it
/// wants otherwise.
pub fn parse_auto<T: FromStr>(s: &str) -> Result<Auto<T>, String>
where
    T::Err: Display,
{
    if s == "auto" {
        return Ok(Auto::Auto);
    }
    s.parse::<T>()
        .map(Auto::Value)
        .map_err(|e| format!("{s}: {e} (a value, or auto)"))
}

#[cfg(test)]
mod tests {
    use super::{parse_auto, Auto};

    /// A knob reads `auto` or a value of its type, takes the value given
    /// over the one `auto` would, and names what it wants otherwise.
    #[test]
    fn a_knob_reads_auto_or_a_value() {
        assert_eq!(parse_auto::<f64>("auto"), Ok(Auto::Auto));
        assert_eq!(parse_auto::<f64>("0.25"), Ok(Auto::Value(0.25)));
        assert_eq!(parse_auto::<f64>("2e-3"), Ok(Auto::Value(2e-3)));
        assert!(parse_auto::<f64>("steep").unwrap_err().contains("or auto"));
        assert_eq!(parse_auto::<u32>("0"), Ok(Auto::Value(0)));
        assert_eq!(parse_auto::<u32>("32"), Ok(Auto::Value(32)));
        assert!(parse_auto::<u32>("big").unwrap_err().contains("or auto"));
        assert!(parse_auto::<u32>("-1").is_err());
        assert_eq!(Auto::Auto.or(0.5), 0.5);
        assert_eq!(Auto::Value(0.0).or(0.5), 0.0);
        assert!(Auto::<u32>::Auto.is_auto() && !Auto::Value(8u32).is_auto());
    }
}

//! What the engine's TOML files share: where a parse error lies, and the
//! `format` and `version` keys that say what a file is.

use serde::de::DeserializeOwned;

/// Parses `text` as `T`; an error as the key it lies at (`line N`, or
/// `toml` where the parser gives no place) and the parser's message.
pub fn parse_toml<T: DeserializeOwned>(text: &str) -> Result<T, (String, String)> {
    toml::from_str(text).map_err(|x: toml::de::Error| {
        let at = x
            .span()
            .map(|s| format!("line {}", text[..s.start].lines().count().max(1)))
            .unwrap_or_else(|| "toml".into());
        (at, x.message().to_owned())
    })
}

/// Checks a file's `format` and `version` against what its reader reads:
/// the key and what is wrong where they differ.
pub fn check_format(
    format: &str,
    version: u32,
    expected_format: &str,
    expected_version: u32,
) -> Result<(), (String, String)> {
    if format != expected_format {
        return Err((
            "format".into(),
            format!("\"{format}\" is not \"{expected_format}\""),
        ));
    }
    if version != expected_version {
        return Err((
            "version".into(),
            format!("{version} is not supported (this reader reads {expected_version})"),
        ));
    }
    Ok(())
}

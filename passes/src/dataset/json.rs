//! Reading a `transforms.json` value by value, so that every error names
//! the file and the key (`frames[3].transform_matrix`).

use std::path::Path;

use glam::DMat4;
use serde_json::{Map, Value};

use super::DatasetError;

/// A JSON object with the file it came from and its key path, for errors.
#[derive(Clone, Copy)]
pub struct Obj<'a> {
    /// The object.
    pub map: &'a Map<String, Value>,
    /// The file.
    pub file: &'a Path,
    /// Its key path ("" at the top, else ending without a dot).
    pub at: &'a str,
}

impl<'a> Obj<'a> {
    /// The full key path of `key` in this object.
    pub fn key(&self, key: &str) -> String {
        if self.at.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.at)
        }
    }

    /// An error at `key`.
    pub fn error(&self, key: &str, message: impl Into<String>) -> DatasetError {
        DatasetError::at(self.file, self.key(key), message)
    }

    /// Whether `key` is present (and not null).
    pub fn has(&self, key: &str) -> bool {
        self.map.get(key).is_some_and(|v| !v.is_null())
    }

    /// An optional finite number.
    pub fn number(&self, key: &str) -> Result<Option<f64>, DatasetError> {
        match self.map.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(self.error(key, format!("expected a finite number, found {v}"))),
            },
        }
    }

    /// An optional string.
    pub fn string(&self, key: &str) -> Result<Option<&'a str>, DatasetError> {
        match self.map.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.as_str())),
            Some(v) => Err(self.error(key, format!("expected a string, found {v}"))),
        }
    }

    /// An optional 4 × 4 matrix given as four rows (the last may be left
    /// out: a 3 × 4 matrix gains the row 0 0 0 1).
    pub fn matrix(&self, key: &str) -> Result<Option<DMat4>, DatasetError> {
        let Some(v) = self.map.get(key).filter(|v| !v.is_null()) else {
            return Ok(None);
        };
        let bad = || self.error(key, "expected 4 rows (or 3) of 4 finite numbers");
        let rows = v.as_array().ok_or_else(bad)?;
        if rows.len() != 4 && rows.len() != 3 {
            return Err(bad());
        }
        let mut m = [[0.0f64; 4]; 4];
        m[3] = [0.0, 0.0, 0.0, 1.0];
        for (r, row) in rows.iter().enumerate() {
            let row = row.as_array().filter(|a| a.len() == 4).ok_or_else(bad)?;
            for (c, x) in row.iter().enumerate() {
                m[r][c] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
            }
        }
        // Rows in the file; glam is column-major.
        Ok(Some(DMat4::from_cols_array_2d(&m).transpose()))
    }

    /// An optional list of `n` finite numbers.
    pub fn numbers(&self, key: &str, n: usize) -> Result<Option<Vec<f64>>, DatasetError> {
        let Some(v) = self.map.get(key).filter(|v| !v.is_null()) else {
            return Ok(None);
        };
        let bad = || self.error(key, format!("expected {n} finite numbers, found {v}"));
        let a = v.as_array().filter(|a| a.len() == n).ok_or_else(bad)?;
        a.iter()
            .map(|x| x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad))
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }
}

/// Parses `text` of `file` as a JSON object.
pub fn parse_object(file: &Path, text: &str) -> Result<Map<String, Value>, DatasetError> {
    let v: Value = serde_json::from_str(text)
        .map_err(|e| DatasetError::at(file, "", format!("not valid JSON: {e}")))?;
    match v {
        Value::Object(m) => Ok(m),
        _ => Err(DatasetError::at(
            file,
            "",
            "expected a JSON object at the top",
        )),
    }
}

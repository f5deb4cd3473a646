//! Three-vectors as scene and environment files write them: an array of
//! exactly three numbers. glam's own deserializer reads the first three
//! of a longer array and drops the rest, so `[0, 0, 3, 5]` passed as
//! `[0, 0, 3]`; fields read through these functions refuse it, naming the
//! length (the loader adds the file and line).

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

/// Reads exactly three `T`s into `V` (`DVec3`, `Vec3`).
pub fn exact<'de, D, T, V>(d: D) -> Result<V, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
    V: From<[T; 3]>,
{
    let v: Vec<T> = Vec::deserialize(d)?;
    let n = v.len();
    let a: [T; 3] = v
        .try_into()
        .map_err(|_| D::Error::invalid_length(n, &"an array of 3 numbers"))?;
    Ok(V::from(a))
}

/// [`exact`] for an optional field (declare it `#[serde(default)]`).
pub fn exact_opt<'de, D, T, V>(d: D) -> Result<Option<V>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
    V: From<[T; 3]>,
{
    Option::<Vec<T>>::deserialize(d)?
        .map(|v| {
            let n = v.len();
            let a: [T; 3] = v
                .try_into()
                .map_err(|_| D::Error::invalid_length(n, &"an array of 3 numbers"))?;
            Ok(V::from(a))
        })
        .transpose()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    struct P {
        #[serde(deserialize_with = "super::exact")]
        v: DVec3,
        #[serde(default, deserialize_with = "super::exact_opt")]
        w: Option<DVec3>,
    }

    #[test]
    fn three_numbers_and_no_other_count() {
        let p: P = toml::from_str("v = [1, 2, 3]").unwrap();
        assert_eq!((p.v, p.w), (DVec3::new(1.0, 2.0, 3.0), None));
        let p: P = toml::from_str("v = [1, 2, 3]\nw = [4, 5, 6]").unwrap();
        assert_eq!(p.w, Some(DVec3::new(4.0, 5.0, 6.0)));
        for bad in [
            "v = [1, 2, 3, 4]",
            "v = [1, 2]",
            "v = [1, 2, 3]\nw = [1, 2, 3, 4]",
        ] {
            let e = toml::from_str::<P>(bad).unwrap_err().to_string();
            assert!(e.contains("expected an array of 3 numbers"), "{bad}: {e}");
        }
    }
}

//! Three-vectors as scene and environment files write them: an array of
//! exactly three numbers. glam's own deserializer reads the first three
//! of a longer array and drops the rest, so `[0, 0, 3, 5]` passed as
//! `[0, 0, 3]`; fields read through these functions refuse it, naming the
//! length (the loader adds the file and line).

use glam::DVec3;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

/// `d` scaled to unit length, for any finite non-zero `d` (exactly
/// `normalize()` where that works): a huge vector, whose length overflows
/// to ∞ and would normalise to zero, or a subnormal one, whose length's
/// inverse overflows, is divided by its largest component first. `None`
/// for zero or non-finite.
pub fn unit(d: DVec3) -> Option<DVec3> {
    if !d.is_finite() {
        return None;
    }
    d.try_normalize().or_else(|| {
        let largest = d.abs().max_element();
        (largest > 0.0).then(|| (d / largest).try_normalize())?
    })
}

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

#[cfg(test)]
mod unit_tests {
    use super::*;

    #[test]
    fn unit_keeps_huge_and_tiny_directions() {
        // Exactly `normalize()` wherever that works.
        let plain = DVec3::new(3.0, 0.0, 4.0);
        assert_eq!(unit(plain), Some(plain.normalize()));
        let huge = unit(DVec3::new(1e308, 1e308, 0.0)).unwrap();
        assert!((huge - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-15);
        let tiny = unit(DVec3::new(0.0, 1e-320, 0.0)).unwrap();
        assert_eq!(tiny, DVec3::Y);
        assert_eq!(unit(DVec3::ZERO), None);
        assert_eq!(unit(DVec3::new(f64::NAN, 1.0, 0.0)), None);
        assert_eq!(unit(DVec3::new(f64::INFINITY, 0.0, 0.0)), None);
    }
}

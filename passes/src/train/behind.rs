//! What is behind the field for a training ray: the fixed background
//! colour, or the [`Sky`] learnt with the field.

use glam::DVec3;

use crate::field::Sky;

/// What is behind the field for a ray: one colour, or a [`Sky`].
#[derive(Debug, Clone, Copy)]
pub enum Behind<'a> {
    /// The same radiance in every direction.
    Colour(DVec3),
    /// A learnt sky.
    Sky(&'a Sky),
}

impl Behind<'_> {
    /// Radiance from unit direction `d`.
    pub fn eval(&self, d: DVec3) -> DVec3 {
        match self {
            Behind::Colour(c) => *c,
            Behind::Sky(s) => s.eval(d),
        }
    }
}

impl From<DVec3> for Behind<'_> {
    fn from(c: DVec3) -> Self {
        Behind::Colour(c)
    }
}

impl<'a> From<&'a Sky> for Behind<'a> {
    fn from(s: &'a Sky) -> Self {
        Behind::Sky(s)
    }
}

//! The object categories of the procedural library.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::error::GeometryError;

/// A kind of household object the library can generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Category {
    /// A bottle: body, shoulder, neck and cap.
    Bottle,
    /// A mug with a handle, hollow and open at the top.
    Mug,
    /// A bowl: a hollow shell with a rim lip and often a foot ring.
    Bowl,
    /// A box with rounded edges, sometimes with a lid.
    Box,
    /// A can with rims and a recessed top, or a plain rounded cylinder.
    Can,
    /// A toy car: body, cabin and four wheels.
    ToyCar,
    /// A stapler or a hole punch: base, hinge and top arm.
    Stapler,
    /// A small toy chair: seat, four legs and a back.
    ToyChair,
    /// A squash or gourd: a bulgy solid of revolution with a neck and a stem.
    Squash,
    /// A random smooth blob.
    Blob,
}

impl Category {
    /// Every category, in manifest order.
    pub const ALL: [Category; 10] = [
        Category::Bottle,
        Category::Mug,
        Category::Bowl,
        Category::Box,
        Category::Can,
        Category::ToyCar,
        Category::Stapler,
        Category::ToyChair,
        Category::Squash,
        Category::Blob,
    ];

    /// The lower-case name used in file names, manifests and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Category::Bottle => "bottle",
            Category::Mug => "mug",
            Category::Bowl => "bowl",
            Category::Box => "box",
            Category::Can => "can",
            Category::ToyCar => "toy_car",
            Category::Stapler => "stapler",
            Category::ToyChair => "toy_chair",
            Category::Squash => "squash",
            Category::Blob => "blob",
        }
    }

    /// A number that identifies the category in seeds; it depends on the name only, so adding
    /// or reordering categories never changes other categories' objects.
    pub(crate) fn seed_salt(self) -> u64 {
        // FNV-1a, 64 bit.
        self.name().bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
        })
    }
}

impl fmt::Display for Category {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Category {
    type Err = GeometryError;

    /// Parses a name such as `mug` or `toy_car` (case-insensitive; `-` works as `_`, and
    /// `hole_punch` means `stapler`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key = s.trim().to_ascii_lowercase().replace('-', "_");
        if key == "hole_punch" {
            return Ok(Category::Stapler);
        }
        Category::ALL
            .into_iter()
            .find(|c| c.name() == key)
            .ok_or_else(|| GeometryError::InvalidParameter {
                op: "object category",
                name: "category",
                value: s.to_string(),
                expected: "one of bottle, mug, bowl, box, can, toy_car, stapler, toy_chair, \
                           squash, blob",
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_salts_differ() {
        for c in Category::ALL {
            assert_eq!(c.name().parse::<Category>().unwrap(), c);
            assert_eq!(c.to_string(), c.name());
        }
        assert_eq!("Toy-Car".parse::<Category>().unwrap(), Category::ToyCar);
        assert_eq!("hole_punch".parse::<Category>().unwrap(), Category::Stapler);
        assert!("teapot".parse::<Category>().is_err());
        let mut salts: Vec<u64> = Category::ALL.iter().map(|c| c.seed_salt()).collect();
        salts.sort_unstable();
        salts.dedup();
        assert_eq!(salts.len(), Category::ALL.len());
    }
}

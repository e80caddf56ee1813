//! The grasp-type label rules: which of the six types (method.md §1, Eq 5.1) suit a point of an
//! object part, from the part's dimensions and whether the point is on its top. The rules and
//! their grounding in Feix et al.'s GRASP taxonomy are documented in models/grasp_type/LABELS.md;
//! keep the two in step.

/// Bit of each type in a label byte, in `GraspType::ALL` order (s = 1…6).
pub const LARGE_WRAP: u8 = 1 << 0;
pub const SMALL_WRAP: u8 = 1 << 1;
pub const POWER: u8 = 1 << 2;
pub const PINCH: u8 = 1 << 3;
pub const PRECISION: u8 = 1 << 4;
pub const TRIPOD: u8 = 1 << 5;

/// Type names in bit order.
pub const NAMES: [&str; 6] = [
    "large_wrap",
    "small_wrap",
    "power",
    "pinch",
    "precision",
    "tripod",
];

/// A surface point counts as "top" when its normal is within 45° of up (cos ≥ 0.7): a hand
/// reaching down can put its fingertips there.
pub const TOP_NORMAL_Z: f64 = 0.7;

/// Dimensions of a part, cm: its three extents sorted `a ≤ b ≤ c`, and its vertical extent `h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartDims {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub h: f64,
}

impl PartDims {
    /// From three extents in metres (any order) and the vertical one.
    pub fn from_extents_m(extents: [f64; 3], vertical: f64) -> Self {
        let mut e = extents.map(|x| x * 100.0);
        e.sort_by(f64::total_cmp);
        Self {
            a: e[0],
            b: e[1],
            c: e[2],
            h: vertical * 100.0,
        }
    }
}

/// The types of a part's side and top surfaces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PartLabels {
    pub side: u8,
    pub top: u8,
}

impl PartLabels {
    /// The label of a surface point with world normal z-component `normal_z`.
    pub fn at(&self, normal_z: f64) -> u8 {
        if normal_z >= TOP_NORMAL_Z {
            self.top
        } else {
            self.side
        }
    }
}

/// The rule set (LABELS.md, one line per type).
pub fn part_labels(d: &PartDims) -> PartLabels {
    let (mut side, mut top) = (0u8, 0u8);
    let mut both = |bit: u8| {
        side |= bit;
        top |= bit;
    };
    // Large diameter: the hand wraps around a thick, elongated part.
    let large_wrap = d.a >= 4.5 && (5.5..=12.0).contains(&d.b) && d.c >= 8.0;
    // Small diameter: handles, bars, bananas — thin and long enough for the whole hand.
    if (0.8..=4.0).contains(&d.a) && d.b <= 4.5 && d.c >= 9.0 {
        both(SMALL_WRAP);
    }
    // Power sphere: the whole part fits into the palm.
    if d.a >= 4.0 && d.c <= 11.0 {
        both(POWER);
    }
    // Pinch: thin (plates, rims) or tiny parts, between thumb and index pads.
    if d.a <= 2.5 || d.c <= 4.0 {
        both(PINCH);
    }
    // Tripod: small parts held by thumb, index and middle tips.
    if d.a >= 1.5 && d.c <= 6.0 {
        both(TRIPOD);
    }
    // Precision (disk/prismatic): all fingertips on the top of a part up to a hand span; on
    // low parts (≤ 5 cm high, e.g. a tuna can) from the side too.
    let precision_top = d.a >= 2.5 && d.b <= 11.0;
    if precision_top {
        top |= PRECISION;
        if d.h <= 5.0 {
            side |= PRECISION;
        }
    }
    // Tripod from above on parts whose top is a few centimetres across.
    if d.a >= 2.5 && d.b <= 5.0 {
        top |= TRIPOD;
    }
    if large_wrap {
        side |= LARGE_WRAP;
    }
    PartLabels { side, top }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(extents_cm: [f64; 3], h: f64) -> PartLabels {
        part_labels(&PartDims::from_extents_m(
            extents_cm.map(|x| x / 100.0),
            h / 100.0,
        ))
    }

    #[test]
    fn tomato_soup_can_wraps_on_the_side_and_is_gripped_from_the_top() {
        // 6.6 cm across, 10.1 cm high.
        let l = labels([6.6, 6.6, 10.1], 10.1);
        assert_eq!(l.side, LARGE_WRAP | POWER);
        assert_eq!(l.top, POWER | PRECISION);
    }

    #[test]
    fn tuna_can_is_a_precision_object_all_round() {
        let l = labels([8.5, 8.5, 3.3], 3.3);
        assert_eq!(l.side, PRECISION);
        assert_eq!(l.top, PRECISION);
    }

    #[test]
    fn a_handle_is_a_small_wrap_and_a_plate_a_pinch() {
        let handle = labels([1.6, 1.6, 12.0], 1.6);
        assert_eq!(handle.side, SMALL_WRAP | PINCH);
        let plate = labels([15.0, 10.0, 0.8], 0.8);
        assert_eq!((plate.side, plate.top), (PINCH, PINCH));
    }

    #[test]
    fn a_small_ball_is_tripod_and_power() {
        let l = labels([5.0, 5.0, 5.0], 5.0);
        assert_eq!(l.side, POWER | TRIPOD | PRECISION);
        assert_eq!(l.top, POWER | TRIPOD | PRECISION);
        assert_eq!(l.at(0.9), l.top);
        assert_eq!(l.at(0.1), l.side);
    }
}

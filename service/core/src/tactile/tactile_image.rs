//! The tactile image t_img (dissertation ch. 6.4, Fig 6.5): an 8 × 5 matrix with each electrode's
//! value at its pixel of the sensor layout; every empty pixel takes the mean of its non-empty
//! neighbours.
//!
//! "Neighbours" are the 8 surrounding pixels. Filling is done in passes: in each pass every empty
//! pixel that has at least one non-empty neighbour takes the mean of those neighbours as they were
//! at the start of the pass (so the result does not depend on scan order); passes repeat until no
//! pixel is empty. With at least one electrode every pixel is reached within 7 passes.

use super::layout::{IMAGE_COLS, IMAGE_ROWS, SensorLayout};

/// An 8 × 5 tactile image; `values[row][col]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TactileImage {
    pub values: [[f64; IMAGE_COLS]; IMAGE_ROWS],
}

impl TactileImage {
    /// Builds the image from a layout and one value per electrode (already tared, so that larger
    /// means more pressure) and fills the empty pixels. `electrodes.len()` must equal the layout's
    /// electrode count (the stabilizer validates this before calling).
    pub fn from_electrodes(layout: &SensorLayout, electrodes: &[f64]) -> Self {
        debug_assert_eq!(layout.electrode_count(), electrodes.len());
        let mut grid = [[None; IMAGE_COLS]; IMAGE_ROWS];
        for (&(r, c), &v) in layout.pixels.iter().zip(electrodes) {
            grid[r][c] = Some(v);
        }
        Self::fill(grid)
    }

    /// Fills the empty (`None`) pixels of a partial image (see the module doc). An image with no
    /// value at all becomes all zeros.
    pub fn fill(mut grid: [[Option<f64>; IMAGE_COLS]; IMAGE_ROWS]) -> Self {
        loop {
            let snapshot = grid;
            let mut empty = 0;
            let mut filled_now = 0;
            for r in 0..IMAGE_ROWS {
                for c in 0..IMAGE_COLS {
                    if snapshot[r][c].is_some() {
                        continue;
                    }
                    empty += 1;
                    let (mut sum, mut n) = (0.0, 0);
                    for dr in -1i32..=1 {
                        for dc in -1i32..=1 {
                            if dr == 0 && dc == 0 {
                                continue;
                            }
                            let (rr, cc) = (r as i32 + dr, c as i32 + dc);
                            if rr < 0
                                || cc < 0
                                || rr >= IMAGE_ROWS as i32
                                || cc >= IMAGE_COLS as i32
                            {
                                continue;
                            }
                            if let Some(v) = snapshot[rr as usize][cc as usize] {
                                sum += v;
                                n += 1;
                            }
                        }
                    }
                    if n > 0 {
                        grid[r][c] = Some(sum / n as f64);
                        filled_now += 1;
                    }
                }
            }
            if empty == 0 || filled_now == 0 {
                break;
            }
        }
        let mut values = [[0.0; IMAGE_COLS]; IMAGE_ROWS];
        for r in 0..IMAGE_ROWS {
            for c in 0..IMAGE_COLS {
                values[r][c] = grid[r][c].unwrap_or(0.0);
            }
        }
        Self { values }
    }

    /// Pixels in row-major order with their (row, col).
    pub fn pixels(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..IMAGE_ROWS).flat_map(move |r| (0..IMAGE_COLS).map(move |c| (r, c, self.values[r][c])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_matches_a_hand_checked_case() {
        // Two known pixels: (0,0) = 8 and (0,2) = 2.
        let mut g = [[None; IMAGE_COLS]; IMAGE_ROWS];
        g[0][0] = Some(8.0);
        g[0][2] = Some(2.0);
        let img = TactileImage::fill(g);
        let v = img.values;
        // Pass 1: (0,1) and (1,1) see both → 5; (1,0) sees only (0,0) → 8; (0,3), (1,2), (1,3)
        // see only (0,2) → 2.
        assert_eq!(v[0][1], 5.0);
        assert_eq!(v[1][1], 5.0);
        assert_eq!(v[1][0], 8.0);
        assert_eq!(v[0][3], 2.0);
        assert_eq!(v[1][2], 2.0);
        assert_eq!(v[1][3], 2.0);
        // Pass 2: (0,4) sees (0,3)=2, (1,3)=2 → 2; (2,0) sees (1,0)=8, (1,1)=5 → 6.5;
        // (2,1) sees (1,0)=8, (1,1)=5, (1,2)=2 → 5; (2,2) sees 5, 2, 2 → 3.
        assert_eq!(v[0][4], 2.0);
        assert_eq!(v[2][0], 6.5);
        assert_eq!(v[2][1], 5.0);
        assert_eq!(v[2][2], 3.0);
        // Pass 3: (3,0) sees (2,0)=6.5, (2,1)=5 → 5.75.
        assert_eq!(v[3][0], 5.75);
        // Every pixel ends up filled with a value between the extremes.
        assert!(img.pixels().all(|(_, _, x)| (2.0..=8.0).contains(&x)));
        // The known pixels are untouched.
        assert_eq!((v[0][0], v[0][2]), (8.0, 2.0));
    }

    #[test]
    fn every_builtin_layout_fills_completely_and_keeps_electrode_values() {
        for l in [SensorLayout::biotac(), SensorLayout::biotac_sp()] {
            let e: Vec<f64> = (0..l.electrode_count()).map(|i| i as f64 + 1.0).collect();
            let img = TactileImage::from_electrodes(&l, &e);
            for (i, &(r, c)) in l.pixels.iter().enumerate() {
                assert_eq!(img.values[r][c], e[i]);
            }
            assert!(
                img.pixels()
                    .all(|(_, _, x)| x >= 1.0 && x <= e.len() as f64)
            );
        }
    }
}

//! A contact slot's candidate set Φ (Eq 5.6), thinned to a spatially even subset so that the
//! solution space has the size the method assumes (the dissertation planned on 120-point clouds;
//! graspd gets thousands), with k-NN lists inside the set for the annealing's local moves.

use crate::cloud::{CloudIndex, LazyNormals};
use nalgebra::Point3;
use std::collections::HashMap;

/// Candidate points of one slot.
#[derive(Debug, Clone)]
pub struct SlotSet {
    /// Point indices, ascending.
    pub points: Vec<usize>,
    member: Vec<bool>,
    /// Neighbours inside the set, per cloud index (empty for non-members). Empty when the set is
    /// the whole cloud: then the cloud's own k-NN lists serve.
    own_neighbours: Vec<Vec<usize>>,
}

/// Neighbours kept per point for local moves.
const K: usize = 8;

impl SlotSet {
    /// Φ(center, radius) thinned to at most `max` points (see [`spread_subset`]).
    pub fn around(
        points: &[Point3<f64>],
        index: &CloudIndex,
        center: &Point3<f64>,
        radius: f64,
        max: usize,
    ) -> Self {
        let near = index.within(center, radius);
        Self::of(points, spread_subset(points, &near, max))
    }

    /// The given points (ascending indices).
    pub fn of(points: &[Point3<f64>], chosen: Vec<usize>) -> Self {
        let mut member = vec![false; points.len()];
        for &i in &chosen {
            member[i] = true;
        }
        let mut own_neighbours = vec![Vec::new(); points.len()];
        for &i in &chosen {
            let mut by_dist: Vec<(f64, usize)> = chosen
                .iter()
                .filter(|&&j| j != i)
                .map(|&j| ((points[j] - points[i]).norm_squared(), j))
                .collect();
            let k = K.min(by_dist.len());
            if k > 0 {
                by_dist.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            }
            own_neighbours[i] = by_dist[..k].iter().map(|x| x.1).collect();
        }
        Self {
            points: chosen,
            member,
            own_neighbours,
        }
    }

    /// Every point of the cloud (the ablation); moves use the cloud's k-NN lists.
    pub fn whole(n: usize) -> Self {
        Self {
            points: (0..n).collect(),
            member: vec![true; n],
            own_neighbours: Vec::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    pub fn contains(&self, i: usize) -> bool {
        self.member.get(i).copied().unwrap_or(false)
    }

    /// Neighbours of `i` inside the set (the cloud's k-NN for the whole cloud).
    pub fn neighbours<'a>(&'a self, i: usize, cloud: &'a LazyNormals) -> &'a [usize] {
        if self.own_neighbours.is_empty() {
            cloud.neighbours(i)
        } else {
            &self.own_neighbours[i]
        }
    }
}

/// At most `max` of `indices`, spread evenly over space: one point per cell of a voxel grid (the
/// one nearest the cell's mean), the cell growing until at most `max` cells are occupied.
/// Deterministic; the result is sorted.
pub fn spread_subset(points: &[Point3<f64>], indices: &[usize], max: usize) -> Vec<usize> {
    if indices.len() <= max || max == 0 {
        return indices.to_vec();
    }
    let (lo, hi) = bounds(points, indices);
    let diag = (hi - lo).norm().max(1e-6);
    let mut cell = diag / (max as f64).sqrt();
    loop {
        let out = voxel_subset(points, indices, cell);
        if out.len() <= max {
            return out;
        }
        cell *= 1.2;
    }
}

fn bounds(points: &[Point3<f64>], indices: &[usize]) -> (Point3<f64>, Point3<f64>) {
    let (mut lo, mut hi) = (points[indices[0]], points[indices[0]]);
    for &i in indices {
        lo = lo.inf(&points[i]);
        hi = hi.sup(&points[i]);
    }
    (lo, hi)
}

/// One of `indices` per occupied cell of a grid of side `cell` (the point nearest the cell's
/// mean). Deterministic; the result is sorted.
pub fn voxel_subset(points: &[Point3<f64>], indices: &[usize], cell: f64) -> Vec<usize> {
    if indices.is_empty() {
        return Vec::new();
    }
    let (lo, _) = bounds(points, indices);
    let mut cells: HashMap<[i64; 3], (nalgebra::Vector3<f64>, Vec<usize>)> = HashMap::new();
    for &i in indices {
        let p = points[i] - lo;
        let key = [
            (p.x / cell) as i64,
            (p.y / cell) as i64,
            (p.z / cell) as i64,
        ];
        let e = cells
            .entry(key)
            .or_insert((nalgebra::Vector3::zeros(), Vec::new()));
        e.0 += points[i].coords;
        e.1.push(i);
    }
    let mut out: Vec<usize> = cells
        .values()
        .map(|(sum, members)| {
            let mean = sum / members.len() as f64;
            *members
                .iter()
                .min_by(|&&a, &&b| {
                    (points[a].coords - mean)
                        .norm_squared()
                        .total_cmp(&(points[b].coords - mean).norm_squared())
                        .then(a.cmp(&b))
                })
                .expect("non-empty cell")
        })
        .collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subset_is_bounded_spread_and_deterministic() {
        let pts: Vec<Point3<f64>> = (0..2500)
            .map(|i| Point3::new((i % 50) as f64 * 0.002, (i / 50) as f64 * 0.002, 0.0))
            .collect();
        let all: Vec<usize> = (0..pts.len()).collect();
        let s = spread_subset(&pts, &all, 100);
        assert!(s.len() <= 100 && s.len() >= 50, "{}", s.len());
        assert_eq!(s, spread_subset(&pts, &all, 100));
        // Spread: every point of the grid has a chosen point within 1.5 cells' diagonal.
        let worst = pts
            .iter()
            .map(|p| {
                s.iter()
                    .map(|&j| (pts[j] - p).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        assert!(worst < 0.02, "{worst}");
        let set = SlotSet::of(&pts, s.clone());
        assert!(set.contains(s[0]) && !set.contains(usize::MAX));
        let idx = CloudIndex::new(&pts);
        let lazy = LazyNormals::new(
            &pts,
            &idx,
            8,
            crate::cloud::Orientation::AwayFromCentroid,
            None,
        );
        assert_eq!(set.neighbours(s[0], &lazy).len(), 8);
    }
}

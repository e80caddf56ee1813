//! A dense bounded primal simplex for the small linear programs the final-configuration search
//! solves thousands of times per plan: the robustness programs ([`super::robustness`]), about
//! 2n + 6 rows and 8n + 1 columns for n contacts.
//!
//! Why not only microlp: its sparse LU machinery costs ≈ 250 µs for one such program of four
//! contacts (measured in session 33), and a plan solves ≈ 70 of them — about 10 ms of a plan whose
//! median target is 20 ms. A dense tableau does the same pivots in a few µs. The shape it takes
//! is the one those programs have, so no phase 1 is needed: maximise c·x subject to rows
//! a_i·x = b_i or a_i·x ≤ b_i with b ≥ 0, 0 ≤ x ≤ u (u may be ∞); x = 0 is feasible. Anything
//! else, or a solve that does not converge, answers None and the caller falls back to microlp.
//!
//! Method: the textbook bounded-variable simplex (Dantzig's largest reduced cost; Bland's
//! smallest index after a run of degenerate pivots, which the programs' zero right-hand sides
//! make common, so it cannot cycle), the final point checked against every row and bound.

/// A row's relation to its right-hand side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Row {
    Eq,
    Le,
}

/// maximise c·x subject to the rows and 0 ≤ x ≤ upper.
#[derive(Debug, Clone, Default)]
pub struct DenseProgram {
    objective: Vec<f64>,
    upper: Vec<f64>,
    /// Row-major coefficients, `objective.len()` per row.
    rows: Vec<f64>,
    kinds: Vec<Row>,
    rhs: Vec<f64>,
}

/// Reduced costs and pivots smaller than this count as zero (the programs' coefficients are O(1)).
const TOLERANCE: f64 = 1e-9;
/// Consecutive degenerate pivots after which Bland's rule takes over.
const DEGENERATE_RUN: usize = 12;

impl DenseProgram {
    /// A variable with objective coefficient `c` and bounds [0, `upper`]; its index.
    pub fn add_var(&mut self, c: f64, upper: f64) -> usize {
        debug_assert!(self.kinds.is_empty(), "variables come before rows");
        self.objective.push(c);
        self.upper.push(upper);
        self.objective.len() - 1
    }

    /// The row Σ coefficient·x `kind` `rhs` (entries naming one variable twice add up).
    pub fn add_row(&mut self, entries: &[(usize, f64)], kind: Row, rhs: f64) {
        let n = self.objective.len();
        let start = self.rows.len();
        self.rows.resize(start + n, 0.0);
        for &(j, a) in entries {
            self.rows[start + j] += a;
        }
        self.kinds.push(kind);
        self.rhs.push(rhs);
    }

    /// The optimum's objective value and point: the dense simplex's, or microlp's where that
    /// one answers None; None when neither solves the program.
    pub fn maximize(&self) -> Option<(f64, Vec<f64>)> {
        self.maximize_dense().or_else(|| {
            tracing::debug!(
                rows = self.kinds.len(),
                columns = self.objective.len(),
                "the dense simplex gave no answer; microlp solves the program"
            );
            self.maximize_microlp()
        })
    }

    /// The same program solved by microlp (the fallback, and the reference in tests).
    pub fn maximize_microlp(&self) -> Option<(f64, Vec<f64>)> {
        use microlp::{ComparisonOp, OptimizationDirection, Problem};
        let n = self.objective.len();
        let mut lp = Problem::new(OptimizationDirection::Maximize);
        let vars: Vec<_> = self
            .objective
            .iter()
            .zip(&self.upper)
            .map(|(&c, &u)| lp.add_var(c, (0.0, u)))
            .collect();
        for (i, (kind, &b)) in self.kinds.iter().zip(&self.rhs).enumerate() {
            let row: Vec<(microlp::Variable, f64)> = self.rows[i * n..(i + 1) * n]
                .iter()
                .zip(&vars)
                .filter(|(a, _)| **a != 0.0)
                .map(|(&a, &v)| (v, a))
                .collect();
            let op = match kind {
                Row::Eq => ComparisonOp::Eq,
                Row::Le => ComparisonOp::Le,
            };
            lp.add_constraint(row.as_slice(), op, b);
        }
        let s = lp.solve().ok()?.into_solution().ok()?;
        Some((s.objective(), vars.iter().map(|&v| s[v]).collect()))
    }

    /// The dense simplex alone: None when the program is not of the module's shape (a
    /// negative right-hand side, a non-finite number), unbounded, or not solved within the
    /// iteration cap with a point that meets every row.
    pub fn maximize_dense(&self) -> Option<(f64, Vec<f64>)> {
        let n = self.objective.len();
        let m = self.kinds.len();
        let finite = self
            .rows
            .iter()
            .chain(&self.objective)
            .all(|a| a.is_finite());
        if !finite || self.rhs.iter().any(|b| !(b.is_finite() && *b >= 0.0)) {
            return None;
        }
        let width = n + m;
        // Tableau [A | I], the slack of an equality row fixed at 0.
        let mut tab = vec![0.0; m * width];
        for i in 0..m {
            tab[i * width..i * width + n].copy_from_slice(&self.rows[i * n..(i + 1) * n]);
            tab[i * width + n + i] = 1.0;
        }
        let mut upper = self.upper.clone();
        upper.extend(self.kinds.iter().map(|k| match k {
            Row::Eq => 0.0,
            Row::Le => f64::INFINITY,
        }));
        let mut reduced: Vec<f64> = self.objective.clone();
        reduced.resize(width, 0.0);
        let mut basis: Vec<usize> = (n..width).collect();
        let mut value = self.rhs.clone();
        let mut in_basis = vec![false; width];
        basis.iter().for_each(|&j| in_basis[j] = true);
        let mut at_upper = vec![false; width];
        let mut degenerate = 0;
        for _ in 0..50 * (width + m) {
            let bland = degenerate >= DEGENERATE_RUN;
            let mut entering: Option<(usize, f64)> = None;
            for j in 0..width {
                if in_basis[j] || upper[j] <= 0.0 {
                    continue;
                }
                let gain = if at_upper[j] { -reduced[j] } else { reduced[j] };
                if gain > TOLERANCE && entering.is_none_or(|(_, g)| !bland && gain > g) {
                    entering = Some((j, gain));
                }
            }
            let Some((j, _)) = entering else {
                return self.checked(n, &basis, &value, &at_upper, &upper);
            };
            // x_j moves by θ in direction σ; basic i moves by −θ σ α_i.
            let sigma = if at_upper[j] { -1.0 } else { 1.0 };
            let mut step = upper[j];
            let mut leaving: Option<(usize, bool)> = None;
            let mut best_pivot = 0.0;
            for i in 0..m {
                let a = sigma * tab[i * width + j];
                let b = basis[i];
                let (limit, to_upper) = if a > TOLERANCE {
                    (value[i].max(0.0) / a, false)
                } else if a < -TOLERANCE && upper[b].is_finite() {
                    ((upper[b] - value[i]).max(0.0) / -a, true)
                } else {
                    continue;
                };
                let better = limit < step - 1e-12
                    || (limit <= step + 1e-12
                        && leaving.is_some()
                        && if bland {
                            b < basis[leaving.map_or(0, |(r, _)| r)]
                        } else {
                            a.abs() > best_pivot
                        });
                if better {
                    step = limit;
                    leaving = Some((i, to_upper));
                    best_pivot = a.abs();
                }
            }
            if !step.is_finite() {
                return None;
            }
            degenerate = if step <= 1e-12 { degenerate + 1 } else { 0 };
            for i in 0..m {
                value[i] -= step * sigma * tab[i * width + j];
            }
            let Some((r, to_upper)) = leaving else {
                // The entering variable reaches its other bound first: no pivot.
                at_upper[j] = !at_upper[j];
                continue;
            };
            let entered = (if at_upper[j] { upper[j] } else { 0.0 }) + sigma * step;
            let left = basis[r];
            in_basis[left] = false;
            at_upper[left] = to_upper;
            in_basis[j] = true;
            at_upper[j] = false;
            basis[r] = j;
            value[r] = entered;
            let pivot = tab[r * width + j];
            let (before, rest) = tab.split_at_mut(r * width);
            let (row_r, after) = rest.split_at_mut(width);
            row_r.iter_mut().for_each(|a| *a /= pivot);
            for row in before.chunks_mut(width).chain(after.chunks_mut(width)) {
                let f = row[j];
                if f != 0.0 {
                    row.iter_mut()
                        .zip(row_r.iter())
                        .for_each(|(a, p)| *a -= f * p);
                }
            }
            let f = reduced[j];
            reduced
                .iter_mut()
                .zip(row_r.iter())
                .for_each(|(a, p)| *a -= f * p);
        }
        None
    }

    /// The point the final basis stands for, if it meets every row and bound to a tolerance
    /// relative to the coefficients (else the pivots lost accuracy: None).
    fn checked(
        &self,
        n: usize,
        basis: &[usize],
        value: &[f64],
        at_upper: &[bool],
        upper: &[f64],
    ) -> Option<(f64, Vec<f64>)> {
        let mut x: Vec<f64> = (0..n)
            .map(|j| if at_upper[j] { upper[j] } else { 0.0 })
            .collect();
        for (&b, &v) in basis.iter().zip(value) {
            if b < n {
                x[b] = v.clamp(0.0, upper[b]);
            }
        }
        for (i, (kind, b)) in self.kinds.iter().zip(&self.rhs).enumerate() {
            let row = &self.rows[i * n..(i + 1) * n];
            let lhs: f64 = row.iter().zip(&x).map(|(a, v)| a * v).sum();
            let scale = 1.0 + row.iter().zip(&x).map(|(a, v)| (a * v).abs()).sum::<f64>();
            let excess = match kind {
                Row::Eq => (lhs - b).abs(),
                Row::Le => lhs - b,
            };
            if excess > 1e-7 * scale {
                return None;
            }
        }
        let objective = self.objective.iter().zip(&x).map(|(c, v)| c * v).sum();
        Some((objective, x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// max 3x + 2y, x + y ≤ 4, x + 3y ≤ 6, x ≤ 3: the optimum (3, 1), value 11 (x at its upper
    /// bound, a bound flip rather than a pivot).
    #[test]
    fn a_two_variable_program_reaches_its_hand_computed_vertex() {
        let mut p = DenseProgram::default();
        let x = p.add_var(3.0, 3.0);
        let y = p.add_var(2.0, f64::INFINITY);
        p.add_row(&[(x, 1.0), (y, 1.0)], Row::Le, 4.0);
        p.add_row(&[(x, 1.0), (y, 3.0)], Row::Le, 6.0);
        let (v, at) = p.maximize().unwrap();
        assert!((v - 11.0).abs() < 1e-12, "{v}");
        assert!(
            (at[0] - 3.0).abs() < 1e-12 && (at[1] - 1.0).abs() < 1e-12,
            "{at:?}"
        );
    }

    /// An equality with a zero right-hand side ties the variables: max t with t = a − b,
    /// a ≤ 2, b ≥ 0 gives t = 2 (a degenerate start: every basic value is 0).
    #[test]
    fn equality_rows_with_zero_right_hand_sides_are_held() {
        let mut p = DenseProgram::default();
        let t = p.add_var(1.0, 1e3);
        let a = p.add_var(0.0, f64::INFINITY);
        let b = p.add_var(0.0, f64::INFINITY);
        p.add_row(&[(t, 1.0), (a, -1.0), (b, 1.0)], Row::Eq, 0.0);
        p.add_row(&[(a, 1.0)], Row::Le, 2.0);
        let (v, at) = p.maximize().unwrap();
        assert!((v - 2.0).abs() < 1e-12, "{v} {at:?}");
        assert!((at[0] - at[1] + at[2]).abs() < 1e-12);
    }

    /// Programs outside the module's shape are refused, not mis-solved: a negative right-hand
    /// side (x = 0 infeasible), an unbounded objective, a NaN.
    #[test]
    fn programs_of_another_shape_answer_none() {
        let mut p = DenseProgram::default();
        let x = p.add_var(1.0, f64::INFINITY);
        p.add_row(&[(x, -1.0)], Row::Le, -1.0);
        assert!(p.maximize().is_none());
        let mut p = DenseProgram::default();
        let x = p.add_var(1.0, f64::INFINITY);
        p.add_row(&[(x, -1.0)], Row::Le, 1.0);
        assert!(p.maximize().is_none());
        let mut p = DenseProgram::default();
        let x = p.add_var(f64::NAN, 1.0);
        p.add_row(&[(x, 1.0)], Row::Le, 1.0);
        assert!(p.maximize().is_none());
    }
}

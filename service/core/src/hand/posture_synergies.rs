//! Hand posture synergies (dissertation §7.3): the low-dimensional posture space of a hand from a
//! principal component analysis of grasp postures, c = c_m + Σ aᵢ eᵢ (Eq 7.3), and the
//! hand-based reward on it (Eq 7.5).
//!
//! A posture is the vector of the model's joint angles (rad). The components are the
//! eigenvectors of the postures' sample covariance in order of falling variance; those with no
//! variance (a joint no grasp moves) are left out. Each grasp type's cluster centre is the mean
//! of its postures' amplitudes (Fig 7.3's red crosses), which Eq 7.5 measures against.
//! The closing synergy that drives the fingers in the planner is another thing
//! (`kinematics::HandSynergy`).

use crate::error::FieldError;
use crate::grasp_type::GraspType;
use nalgebra::{DMatrix, SymmetricEigen};

/// A component whose variance is under this fraction of the total is no component (rounding).
const NEGLIGIBLE_VARIANCE: f64 = 1e-12;

/// Components in the amplitude vector A of Eq 7.5 (the dissertation's n = 2).
pub const REWARD_COMPONENTS: usize = 2;

/// One grasp posture and the type it realises.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledPosture {
    pub joints: Vec<f64>,
    pub grasp_type: GraspType,
}

/// A principal component eᵢ.
#[derive(Debug, Clone, PartialEq)]
pub struct SynergyComponent {
    /// Unit vector over the joints; its largest entry (the first of equal ones) is positive, so
    /// the sign is reproducible.
    pub direction: Vec<f64>,
    /// Variance of the postures along it, rad².
    pub variance: f64,
    /// Its share of the postures' total variance.
    pub explained: f64,
}

/// The cluster centre of one grasp type's postures in the posture space.
#[derive(Debug, Clone, PartialEq)]
pub struct TypeCentre {
    pub grasp_type: GraspType,
    /// Postures of this type.
    pub postures: usize,
    /// Mean amplitude on each component (as many as there are components).
    pub amplitudes: Vec<f64>,
}

/// A hand's posture space (Eq 7.3).
#[derive(Debug, Clone, PartialEq)]
pub struct PostureSynergies {
    /// Joint names, the order of every vector here.
    pub joints: Vec<String>,
    /// The nominal posture c_m: the postures' mean.
    pub mean: Vec<f64>,
    /// In order of falling variance.
    pub components: Vec<SynergyComponent>,
    /// Per grasp type present, in the order s = 1..6.
    pub centres: Vec<TypeCentre>,
    /// Postures fitted.
    pub postures: usize,
}

impl PostureSynergies {
    /// Fits the posture space to `postures` (each with one angle per name in `joints`).
    pub fn fit(joints: Vec<String>, postures: &[LabelledPosture]) -> Result<Self, FieldError> {
        let d = joints.len();
        if postures.len() < 2 {
            return Err(FieldError::new(
                "postures",
                format!(
                    "a posture space needs at least 2 postures, got {}",
                    postures.len()
                ),
            ));
        }
        for (i, p) in postures.iter().enumerate() {
            if p.joints.len() != d {
                return Err(FieldError::new(
                    format!("postures[{i}]"),
                    format!("has {} joint angles, the hand {d}", p.joints.len()),
                ));
            }
            if p.joints.iter().any(|x| !x.is_finite()) {
                return Err(FieldError::new(
                    format!("postures[{i}]"),
                    "a joint angle is not finite",
                ));
            }
        }
        let n = postures.len() as f64;
        let mean: Vec<f64> = (0..d)
            .map(|j| postures.iter().map(|p| p.joints[j]).sum::<f64>() / n)
            .collect();
        let centred = DMatrix::from_fn(postures.len(), d, |i, j| postures[i].joints[j] - mean[j]);
        let covariance = centred.transpose() * &centred / (n - 1.0);
        let eigen = SymmetricEigen::new(covariance);
        let total: f64 = eigen.eigenvalues.iter().map(|v| v.max(0.0)).sum();
        let mut order: Vec<usize> = (0..d).collect();
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        let components: Vec<SynergyComponent> = order
            .into_iter()
            .filter(|&k| total > 0.0 && eigen.eigenvalues[k] > NEGLIGIBLE_VARIANCE * total)
            .map(|k| {
                let mut direction: Vec<f64> =
                    eigen.eigenvectors.column(k).iter().copied().collect();
                let largest = direction.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                let first = direction
                    .iter()
                    .position(|x| x.abs() >= largest - 1e-9)
                    .unwrap_or(0);
                if direction[first] < 0.0 {
                    direction.iter_mut().for_each(|x| *x = -*x);
                }
                SynergyComponent {
                    direction,
                    variance: eigen.eigenvalues[k],
                    explained: eigen.eigenvalues[k] / total,
                }
            })
            .collect();
        let mut space = Self {
            joints,
            mean,
            components,
            centres: Vec::new(),
            postures: postures.len(),
        };
        let m = space.components.len();
        for t in GraspType::ALL {
            let of_type: Vec<&LabelledPosture> =
                postures.iter().filter(|p| p.grasp_type == t).collect();
            if of_type.is_empty() {
                continue;
            }
            let mut amplitudes = vec![0.0; m];
            for p in &of_type {
                for (a, x) in amplitudes.iter_mut().zip(space.amplitudes(&p.joints, m)) {
                    *a += x / of_type.len() as f64;
                }
            }
            space.centres.push(TypeCentre {
                grasp_type: t,
                postures: of_type.len(),
                amplitudes,
            });
        }
        Ok(space)
    }

    /// The amplitudes aᵢ = eᵢ · (c − c_m) of `posture` on the first `n` components (fewer if the
    /// space has fewer).
    pub fn amplitudes(&self, posture: &[f64], n: usize) -> Vec<f64> {
        self.components
            .iter()
            .take(n)
            .map(|e| {
                e.direction
                    .iter()
                    .zip(posture.iter().zip(&self.mean))
                    .map(|(e, (c, m))| e * (c - m))
                    .sum()
            })
            .collect()
    }

    /// The posture of amplitudes `a` on the first components (Eq 7.3).
    pub fn posture(&self, a: &[f64]) -> Vec<f64> {
        let mut c = self.mean.clone();
        for (e, ai) in self.components.iter().zip(a) {
            for (cj, ej) in c.iter_mut().zip(&e.direction) {
                *cj += ai * ej;
            }
        }
        c
    }

    /// d_hand of Eq 7.5: the squared distance of `posture`'s amplitude vector A = [a₁, a₂] from
    /// `grasp_type`'s centre; None where the type has no postures here.
    pub fn hand_distance(&self, posture: &[f64], grasp_type: GraspType) -> Option<f64> {
        let centre = self.centres.iter().find(|c| c.grasp_type == grasp_type)?;
        let a = self.amplitudes(posture, REWARD_COMPONENTS);
        Some(
            a.iter()
                .zip(&centre.amplitudes)
                .map(|(x, c)| (x - c).powi(2))
                .sum(),
        )
    }
}

/// The hand-based reward r_hand of Eq 7.5 for a distance d_hand: 1.5 within 0.4 of the
/// precision centre, falling linearly from 0 to −1 over [0.4, 1.4], −10 beyond.
pub fn hand_based_reward(d_hand: f64) -> f64 {
    if d_hand < 0.4 {
        1.5
    } else if d_hand <= 1.4 {
        -(d_hand - 0.4) / (1.4 - 0.4)
    } else {
        -10.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use GraspType::*;

    fn posture(joints: &[f64], grasp_type: GraspType) -> LabelledPosture {
        LabelledPosture {
            joints: joints.to_vec(),
            grasp_type,
        }
    }

    /// Four postures of two joints, mean 0: covariance [[10, 6], [6, 10]] / 3, so the
    /// components are (1, 1)/√2 with variance 16/3 (80 %) and (1, −1)/√2 with 4/3 (20 %).
    fn square() -> PostureSynergies {
        PostureSynergies::fit(
            vec!["a".into(), "b".into()],
            &[
                posture(&[2.0, 2.0], Precision),
                posture(&[-2.0, -2.0], Power),
                posture(&[1.0, -1.0], Precision),
                posture(&[-1.0, 1.0], Power),
            ],
        )
        .unwrap()
    }

    #[test]
    fn components_match_the_hand_computed_covariance() {
        let s = square();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert_eq!(s.postures, 4);
        assert_eq!(s.mean, vec![0.0, 0.0]);
        assert_eq!(s.components.len(), 2);
        let (e1, e2) = (&s.components[0], &s.components[1]);
        assert!((e1.variance - 16.0 / 3.0).abs() < 1e-12, "{}", e1.variance);
        assert!((e2.variance - 4.0 / 3.0).abs() < 1e-12, "{}", e2.variance);
        assert!((e1.explained - 0.8).abs() < 1e-12);
        assert!((e2.explained - 0.2).abs() < 1e-12);
        for (got, want) in e1.direction.iter().zip([h, h]) {
            assert!((got - want).abs() < 1e-12, "{:?}", e1.direction);
        }
        for (got, want) in e2.direction.iter().zip([h, -h]) {
            assert!((got - want).abs() < 1e-12, "{:?}", e2.direction);
        }
    }

    #[test]
    fn centres_and_amplitudes_round_trip_through_eq_7_3() {
        let s = square();
        let r2 = std::f64::consts::SQRT_2;
        // Precision: (2, 2) → (2√2, 0) and (1, −1) → (0, √2); their mean (√2, √2/2).
        let precision = s
            .centres
            .iter()
            .find(|c| c.grasp_type == Precision)
            .unwrap();
        assert_eq!(precision.postures, 2);
        assert!((precision.amplitudes[0] - r2).abs() < 1e-12);
        assert!((precision.amplitudes[1] - r2 / 2.0).abs() < 1e-12);
        let order: Vec<GraspType> = s.centres.iter().map(|c| c.grasp_type).collect();
        assert_eq!(order, [Power, Precision]);
        let c = s.posture(&s.amplitudes(&[0.3, -1.7], 2));
        assert!(
            (c[0] - 0.3).abs() < 1e-12 && (c[1] + 1.7).abs() < 1e-12,
            "{c:?}"
        );
        // d_hand of (2, 2) from the precision centre: (2√2 − √2)² + (0 − √2/2)² = 2.5.
        let d = s.hand_distance(&[2.0, 2.0], Precision).unwrap();
        assert!((d - 2.5).abs() < 1e-12, "{d}");
        assert_eq!(s.hand_distance(&[2.0, 2.0], Tripod), None);
    }

    #[test]
    fn a_joint_no_posture_moves_gives_no_component() {
        let s = PostureSynergies::fit(
            vec!["a".into(), "b".into(), "fixed".into()],
            &[
                posture(&[0.0, 1.0, 0.5], Pinch),
                posture(&[1.0, 0.0, 0.5], Pinch),
                posture(&[2.0, 1.0, 0.5], Pinch),
            ],
        )
        .unwrap();
        assert_eq!(s.mean[2], 0.5);
        assert_eq!(s.components.len(), 2);
        for e in &s.components {
            assert!(e.direction[2].abs() < 1e-9, "{:?}", e.direction);
        }
        let sum: f64 = s.components.iter().map(|e| e.explained).sum();
        assert!((sum - 1.0).abs() < 1e-12);
    }

    #[test]
    fn too_few_or_ragged_postures_are_refused_naming_them() {
        let one = PostureSynergies::fit(vec!["a".into()], &[posture(&[0.0], Pinch)]);
        assert_eq!(one.unwrap_err().field, "postures");
        let ragged = PostureSynergies::fit(
            vec!["a".into(), "b".into()],
            &[posture(&[0.0, 1.0], Pinch), posture(&[0.0], Pinch)],
        );
        assert_eq!(ragged.unwrap_err().field, "postures[1]");
        let nan = PostureSynergies::fit(
            vec!["a".into()],
            &[posture(&[0.0], Pinch), posture(&[f64::NAN], Pinch)],
        );
        assert_eq!(nan.unwrap_err().field, "postures[1]");
    }

    #[test]
    fn the_hand_based_reward_follows_eq_7_5() {
        assert_eq!(hand_based_reward(0.0), 1.5);
        assert_eq!(hand_based_reward(0.39), 1.5);
        assert_eq!(hand_based_reward(0.4), 0.0);
        assert!((hand_based_reward(0.9) + 0.5).abs() < 1e-12);
        assert!((hand_based_reward(1.4) + 1.0).abs() < 1e-12);
        assert_eq!(hand_based_reward(1.41), -10.0);
    }
}

//! A scene for the planning stages' unit tests: a rod (or another object) on a table, seen
//! from above, and the search context of a built-in hand on it.

use super::evaluation::SearchContext;
use super::object_shape::ObjectShape;
use super::request::PlannerOptions;
use crate::cloud::{CloudIndex, LazyNormals, Orientation, Plane};
use crate::grasp_type::GraspType;
use crate::hand::{HandCatalog, HandDescription, ResolvedGrasp};
use nalgebra::{Point3, Vector3};

/// A rod `length` m long and 4 cm across lying along x on the table z = 0, centred on the
/// origin: its top half-cylinder every 5 mm, with a built-in hand's grasp of one type.
pub struct Rod {
    pub points: Vec<Point3<f64>>,
    pub index: CloudIndex,
    pub shape: ObjectShape,
    pub hand: HandDescription,
    pub grasp: ResolvedGrasp,
    pub options: PlannerOptions,
}

impl Rod {
    pub fn new(length: f64, hand: &str, grasp_type: GraspType) -> Self {
        let steps = (length / 0.005).round() as usize;
        let mut points = Vec::new();
        for i in 0..=steps {
            for k in 0..=12 {
                let a = std::f64::consts::PI * k as f64 / 12.0;
                points.push(Point3::new(
                    -length / 2.0 + 0.005 * i as f64,
                    0.02 * a.cos(),
                    0.02 + 0.02 * a.sin(),
                ));
            }
        }
        Self::with_points(points, hand, grasp_type)
    }

    /// Another object on the table z = 0 (its points), with a built-in hand's grasp of one type.
    pub fn with_points(points: Vec<Point3<f64>>, hand: &str, grasp_type: GraspType) -> Self {
        let hand = HandCatalog::builtin().get(hand).unwrap().clone();
        let grasp = hand.resolve_forced(grasp_type).unwrap();
        Self {
            index: CloudIndex::new(&points),
            shape: ObjectShape::of(&points),
            points,
            hand,
            grasp,
            options: PlannerOptions::default(),
        }
    }

    /// Normals facing the camera above.
    pub fn normals(&self) -> LazyNormals<'_> {
        let view = Point3::new(0.0, 0.0, 1.0);
        LazyNormals::new(
            &self.points,
            &self.index,
            12,
            Orientation::TowardViewpoint(view),
            None,
        )
    }

    /// Normals facing away from the centroid: every face seen (a wall's normal points out,
    /// where [`Self::normals`] turns it toward the axis).
    pub fn normals_outward(&self) -> LazyNormals<'_> {
        LazyNormals::new(
            &self.points,
            &self.index,
            12,
            Orientation::AwayFromCentroid,
            None,
        )
    }

    /// The point nearest to `p`.
    pub fn nearest(&self, p: Point3<f64>) -> usize {
        self.index.nearest_one(&p).0
    }

    /// The search context with the attention point at point `att`, approached from above.
    pub fn context<'a>(&'a self, normals: &'a LazyNormals<'a>, att: usize) -> SearchContext<'a> {
        SearchContext {
            points: &self.points,
            normals,
            index: &self.index,
            shape: &self.shape,
            hand: &self.hand,
            grasp: &self.grasp,
            p_att: self.points[att],
            n_att: normals.get(att),
            approach_prefs: vec![-Vector3::z()],
            plane: Some(Plane::through(&Point3::origin(), Vector3::z())),
            options: &self.options,
            cos_friction: self.options.friction.atan().cos(),
            collision_checks: false,
        }
    }
}

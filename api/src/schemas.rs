//! OpenAPI schemas for the domain types the REST JSON carries as they are (grasp types, hand
//! descriptions, planner options, the numeric report structs, the tactile settings). They live
//! in `graspd_core`, which knows nothing of transports, so they are described here: enums by
//! their serialised names (a new variant fails to compile until it is listed), report structs
//! by the serde form of a value of them (property names and JSON types, none marked required),
//! and the rest as objects with a pointer to their documentation. [`crate::json`]'s DTOs name
//! them in `#[schema(value_type = …)]`.

use graspd_core::perception::{PerceptionTimings, TargetChoice};
use graspd_core::planning::{
    CollisionReport, LearnedQuality, PlaneSource, PlannerMode, Quality, StageStats, Timings,
    TypeSource,
};
use graspd_core::tactile::{ElectrodePolarity, ModelFreeThresholds, PidGains};
use graspd_core::{GraspType, HandPart, PlannerOptions};
use serde::Serialize;
use serde_json::Value;
use std::borrow::Cow;
use utoipa::openapi::RefOr;
use utoipa::openapi::schema::{
    AdditionalProperties, ArrayBuilder, ObjectBuilder, OneOfBuilder, Schema, SchemaType, Type,
};
use utoipa::{PartialSchema, ToSchema};

/// A schema type for a domain type: `name` in the document, `schema` its description.
macro_rules! doc_schema {
    ($(#[$m:meta])* $doc:ident, $name:literal, $schema:expr) => {
        $(#[$m])*
        pub struct $doc;
        impl PartialSchema for $doc {
            fn schema() -> RefOr<Schema> {
                $schema
            }
        }
        impl ToSchema for $doc {
            fn name() -> Cow<'static, str> {
                Cow::Borrowed($name)
            }
        }
    };
}

/// A string enum of the domain type's serde names; the `match` makes a new variant a compile
/// error here.
macro_rules! enum_schema {
    ($ty:ty, [$($v:path),+ $(,)?], $description:literal) => {{
        let _exhaustive = |x: $ty| match x {
            $($v => ()),+
        };
        string_enum(&[$($v),+], $description)
    }};
}

fn string_enum<T: Serialize>(values: &[T], description: &str) -> RefOr<Schema> {
    let names: Vec<Value> = values
        .iter()
        .map(|v| serde_json::to_value(v).expect("an enum serialises to its name"))
        .collect();
    ObjectBuilder::new()
        .schema_type(Type::String)
        .enum_values(Some(names))
        .description(Some(description))
        .build()
        .into()
}

/// The schema of a value's serde form: objects with their properties, JSON types, array items
/// from the first element; `null` (an unset `Option`) as any value. Nothing is marked required.
fn shape_of(value: &Value) -> RefOr<Schema> {
    let schema: Schema = match value {
        Value::Null => ObjectBuilder::new()
            .schema_type(SchemaType::AnyValue)
            .build()
            .into(),
        Value::Bool(_) => ObjectBuilder::new()
            .schema_type(Type::Boolean)
            .build()
            .into(),
        Value::Number(n) if n.is_f64() => ObjectBuilder::new()
            .schema_type(Type::Number)
            .build()
            .into(),
        Value::Number(_) => ObjectBuilder::new()
            .schema_type(Type::Integer)
            .build()
            .into(),
        Value::String(_) => ObjectBuilder::new()
            .schema_type(Type::String)
            .build()
            .into(),
        Value::Array(items) => {
            let mut array = ArrayBuilder::new();
            if let Some(first) = items.first() {
                array = array.items(shape_of(first));
            }
            array.build().into()
        }
        Value::Object(map) => {
            let mut object = ObjectBuilder::new().schema_type(Type::Object);
            for (name, v) in map {
                object = object.property(name, shape_of(v));
            }
            object.build().into()
        }
    };
    RefOr::T(schema)
}

/// [`shape_of`] a value, described.
fn shape<T: Serialize>(value: &T, description: &str) -> RefOr<Schema> {
    let value = serde_json::to_value(value).expect("a domain value serialises");
    match shape_of(&value) {
        RefOr::T(Schema::Object(mut o)) => {
            o.description = Some(description.into());
            RefOr::T(Schema::Object(o))
        }
        other => other,
    }
}

/// An object whose shape is documented elsewhere.
fn object(description: &str) -> RefOr<Schema> {
    ObjectBuilder::new()
        .schema_type(Type::Object)
        .description(Some(description))
        .build()
        .into()
}

fn one_of(b: OneOfBuilder) -> RefOr<Schema> {
    RefOr::T(Schema::OneOf(b.build()))
}

fn number_triple() -> ArrayBuilder {
    ArrayBuilder::new()
        .items(ObjectBuilder::new().schema_type(Type::Number))
        .min_items(Some(3))
        .max_items(Some(3))
}

fn vec3_object() -> ObjectBuilder {
    ObjectBuilder::new()
        .schema_type(Type::Object)
        .property("x", ObjectBuilder::new().schema_type(Type::Number))
        .property("y", ObjectBuilder::new().schema_type(Type::Number))
        .property("z", ObjectBuilder::new().schema_type(Type::Number))
        .required("x")
        .required("y")
        .required("z")
        .additional_properties(Some(AdditionalProperties::FreeForm(false)))
}

doc_schema!(
    /// A position or direction in a request: `{x, y, z}` or `[x, y, z]` (answers write the
    /// object form).
    Vec3InputDoc,
    "Vec3Input",
    one_of(OneOfBuilder::new()
        .item(vec3_object())
        .item(number_triple())
        .description(Some("{x, y, z} or [x, y, z]; metres in the input's frame"))
    )
);

doc_schema!(
    Vec3ListDoc,
    "Vec3List",
    one_of(
        OneOfBuilder::new()
            .item(ArrayBuilder::new().items(number_triple()))
            .item(
                ObjectBuilder::new()
                    .schema_type(Type::String)
                    .content_encoding("base64")
                    .description(Some("packed little-endian float32 x, y, z triples"))
            )
            .description(Some(
                "Points as [[x, y, z], …] or as base64 of packed little-endian float32 triples"
            ))
    )
);

doc_schema!(
    GraspTypeDoc,
    "GraspType",
    enum_schema!(
        GraspType,
        [
            GraspType::LargeWrap,
            GraspType::SmallWrap,
            GraspType::Power,
            GraspType::Pinch,
            GraspType::Precision,
            GraspType::Tripod,
        ],
        "A grasp type (the dissertation's six)"
    )
);

doc_schema!(
    HandPartDoc,
    "HandPart",
    enum_schema!(
        HandPart,
        [
            HandPart::ThumbTip,
            HandPart::ThumbSurface,
            HandPart::FingerTip,
            HandPart::FingerSurface,
            HandPart::Palm,
        ],
        "A hand part: thumb tip, thumb surface, finger tip, finger surface, palm"
    )
);

doc_schema!(
    TypeSourceDoc,
    "TypeSource",
    enum_schema!(
        TypeSource,
        [
            TypeSource::Request,
            TypeSource::GeometricRule,
            TypeSource::Model
        ],
        "Who decided the grasp type"
    )
);

doc_schema!(
    PlaneSourceDoc,
    "PlaneSource",
    enum_schema!(
        PlaneSource,
        [
            PlaneSource::Request,
            PlaneSource::Detected,
            PlaneSource::None
        ],
        "Where the support plane came from"
    )
);

doc_schema!(
    PlannerModeDoc,
    "PlannerMode",
    enum_schema!(
        PlannerMode,
        [
            PlannerMode::DualStage,
            PlannerMode::WithoutOpposition,
            PlannerMode::LearnedQuality
        ],
        "The planner's mode"
    )
);

doc_schema!(
    TargetChoiceDoc,
    "TargetChoice",
    enum_schema!(
        TargetChoice,
        [
            TargetChoice::Pixel,
            TargetChoice::Region,
            TargetChoice::Object,
            TargetChoice::Saliency,
            TargetChoice::ImageCentre,
        ],
        "What decided the RGB-D target"
    )
);

doc_schema!(
    ElectrodePolarityDoc,
    "ElectrodePolarity",
    enum_schema!(
        ElectrodePolarity,
        [ElectrodePolarity::Falling, ElectrodePolarity::Rising],
        "Which way electrode readings move under pressure"
    )
);

doc_schema!(
    TareConfigDoc,
    "TareConfig",
    object(
        "Taring in the domain's serde form (graspd_core::tactile::TareConfig): {\"baseline\": {\"first_frames\": 50} or \"none\" (pretared), \"electrode_polarity\": \"falling\" | \"rising\"}"
    )
);

doc_schema!(
    QualityDoc,
    "Quality",
    shape(
        &Quality {
            gii: 0.0,
            reachability: 0.0,
            attention: 0.0,
            objective: 0.0,
            epsilon: 0.0,
            aperture_or_area: 0.0,
            palm_height: 0.0,
            robustness: 0.0,
            gravity_resistance: 0.0,
        },
        "Quality of the final grasp (graspd_core::planning::Quality)"
    )
);

doc_schema!(
    LearnedQualityDoc,
    "LearnedQuality",
    shape(
        &LearnedQuality {
            probability: 0.0,
            posterior_mean: 0.0,
            posterior_std: 0.0,
            network_calls: 0,
            candidates: 0,
        },
        "The learned-quality search's result (graspd_core::planning::LearnedQuality): the \
         network's P(success) of the executed grasp, the Gaussian process's posterior there, \
         the network calls made and the candidates chosen among"
    )
);

doc_schema!(
    StageStatsDoc,
    "StageStats",
    shape(
        &StageStats::default(),
        "Search statistics of one stage (graspd_core::planning::StageStats)"
    )
);

doc_schema!(
    TimingsDoc,
    "Timings",
    shape(
        &Timings::default(),
        "Wall time per step of the plan, seconds (graspd_core::planning::Timings)"
    )
);

doc_schema!(
    CollisionReportDoc,
    "CollisionReport",
    shape(
        &CollisionReport::default(),
        "Collision status of the planned hand; clearances in metres or null (graspd_core::planning::CollisionReport)"
    )
);

doc_schema!(
    PerceptionTimingsDoc,
    "PerceptionTimings",
    shape(
        &PerceptionTimings::default(),
        "Wall time per perception step, seconds (graspd_core::perception::PerceptionTimings)"
    )
);

doc_schema!(
    PlannerOptionsDoc,
    "PlannerOptions",
    shape(
        &PlannerOptions::default(),
        "Every planner parameter; unset ones take their defaults (PlannerOptions in service/core/src/planning/request.rs). The properties and their types are those of the defaults; fields that default to null take the documented type."
    )
);

doc_schema!(
    ModelFreeThresholdsDoc,
    "ModelFreeThresholds",
    shape(
        &ModelFreeThresholds::default(),
        "Thresholds of the model-free contact/slip detector (graspd_core::tactile::ModelFreeThresholds)"
    )
);

doc_schema!(
    PidGainsDoc,
    "PidGains",
    shape(
        &PidGains::default(),
        "The force controller's gains (graspd_core::tactile::PidGains)"
    )
);

doc_schema!(
    HandDescriptionDoc,
    "HandDescription",
    object(
        "A parametric hand description in the domain's serde form (HandDescription in service/core/src/hand/description.rs; the README's Hands section)"
    )
);

doc_schema!(
    LayoutDoc,
    "Layout",
    one_of(OneOfBuilder::new()
        .item(
            ObjectBuilder::new()
                .schema_type(Type::String)
                .description(Some("a built-in layout: biotac or biotac_sp"))
        )
        .item(object(
            "a custom layout {\"name\", \"electrodes\": [[x_mm, y_mm], …]} (graspd_core::tactile::LayoutSpec)"
        ))
        .description(Some("A finger's electrode layout"))
    )
);

doc_schema!(
    DetectorDoc,
    "Detector",
    one_of(OneOfBuilder::new()
        .item(
            ObjectBuilder::new()
                .schema_type(Type::Object)
                .property("model_free", ModelFreeThresholdsDoc::schema())
                .required("model_free")
                .additional_properties(Some(AdditionalProperties::FreeForm(false)))
        )
        .item(
            ObjectBuilder::new()
                .schema_type(Type::Object)
                .property("model", ObjectBuilder::new().schema_type(Type::String))
                .required("model")
                .additional_properties(Some(AdditionalProperties::FreeForm(false)))
        )
        .item(
            ObjectBuilder::new()
                .schema_type(Type::Object)
                .property("calibration", ObjectBuilder::new().schema_type(Type::String))
                .required("calibration")
                .additional_properties(Some(AdditionalProperties::FreeForm(false)))
        )
        .description(Some(
            "{\"model_free\": {thresholds}}, {\"model\": \"lstm\"} (the learned LSTM detector of models/tactile; 400 when none is loaded or the session does not fit it) or {\"calibration\": \"name\"} (a calibration of POST /v1/tactile/calibrations; 400 when unknown or when the session's window, stride, electrodes or taring differ from its). Absent: the loaded model when the session fits it, else model_free with default thresholds"
        ))
    )
);

doc_schema!(
    FrameResultDoc,
    "FrameResult",
    object(
        "One frame's result in the domain's serde form (graspd_core::tactile::FrameResult; the fields of the proto's StabilizationSetpoint): timestamp and per-finger setpoints, enums as snake_case names, probabilities and locations as arrays, absent values as null"
    )
);

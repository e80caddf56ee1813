//! A minimal ONNX model writer for tests: the subset of `onnx.proto` (onnx/onnx, proto2) needed
//! for small graphs of standard operators with float initializers, encoded with prost. Field
//! numbers follow onnx.proto; proto2 `repeated int64` fields are not packed there, so they are
//! written unpacked here.
//!
//! Use from a test crate with `#[path = "common/onnx_builder.rs"] mod onnx_builder;`.

#![allow(dead_code)]

use prost::Message;

/// `TensorProto.DataType`.
pub const FLOAT: i32 = 1;
pub const DOUBLE: i32 = 11;

/// `AttributeProto.AttributeType`.
const ATTR_INT: i32 = 2;
const ATTR_INTS: i32 = 7;

#[derive(Clone, PartialEq, Message)]
pub struct ModelProto {
    #[prost(int64, tag = "1")]
    pub ir_version: i64,
    #[prost(string, tag = "2")]
    pub producer_name: String,
    #[prost(message, optional, tag = "7")]
    pub graph: Option<GraphProto>,
    #[prost(message, repeated, tag = "8")]
    pub opset_import: Vec<OperatorSetIdProto>,
    #[prost(message, repeated, tag = "14")]
    pub metadata_props: Vec<StringStringEntryProto>,
}

#[derive(Clone, PartialEq, Message)]
pub struct OperatorSetIdProto {
    #[prost(string, tag = "1")]
    pub domain: String,
    #[prost(int64, tag = "2")]
    pub version: i64,
}

#[derive(Clone, PartialEq, Message)]
pub struct StringStringEntryProto {
    #[prost(string, tag = "1")]
    pub key: String,
    #[prost(string, tag = "2")]
    pub value: String,
}

#[derive(Clone, PartialEq, Message)]
pub struct GraphProto {
    #[prost(message, repeated, tag = "1")]
    pub node: Vec<NodeProto>,
    #[prost(string, tag = "2")]
    pub name: String,
    #[prost(message, repeated, tag = "5")]
    pub initializer: Vec<TensorProto>,
    #[prost(message, repeated, tag = "11")]
    pub input: Vec<ValueInfoProto>,
    #[prost(message, repeated, tag = "12")]
    pub output: Vec<ValueInfoProto>,
}

#[derive(Clone, PartialEq, Message)]
pub struct NodeProto {
    #[prost(string, repeated, tag = "1")]
    pub input: Vec<String>,
    #[prost(string, repeated, tag = "2")]
    pub output: Vec<String>,
    #[prost(string, tag = "3")]
    pub name: String,
    #[prost(string, tag = "4")]
    pub op_type: String,
    #[prost(message, repeated, tag = "5")]
    pub attribute: Vec<AttributeProto>,
}

#[derive(Clone, PartialEq, Message)]
pub struct AttributeProto {
    #[prost(string, tag = "1")]
    pub name: String,
    #[prost(int64, optional, tag = "3")]
    pub i: Option<i64>,
    #[prost(int64, repeated, packed = "false", tag = "8")]
    pub ints: Vec<i64>,
    #[prost(int32, tag = "20")]
    pub r#type: i32,
}

#[derive(Clone, PartialEq, Message)]
pub struct TensorProto {
    #[prost(int64, repeated, packed = "false", tag = "1")]
    pub dims: Vec<i64>,
    #[prost(int32, tag = "2")]
    pub data_type: i32,
    #[prost(float, repeated, tag = "4")]
    pub float_data: Vec<f32>,
    #[prost(string, tag = "8")]
    pub name: String,
    #[prost(bytes = "vec", tag = "9")]
    pub raw_data: Vec<u8>,
}

#[derive(Clone, PartialEq, Message)]
pub struct ValueInfoProto {
    #[prost(string, tag = "1")]
    pub name: String,
    #[prost(message, optional, tag = "2")]
    pub r#type: Option<TypeProto>,
}

#[derive(Clone, PartialEq, Message)]
pub struct TypeProto {
    #[prost(message, optional, tag = "1")]
    pub tensor_type: Option<TypeProtoTensor>,
}

/// `TypeProto.Tensor`.
#[derive(Clone, PartialEq, Message)]
pub struct TypeProtoTensor {
    #[prost(int32, tag = "1")]
    pub elem_type: i32,
    #[prost(message, optional, tag = "2")]
    pub shape: Option<TensorShapeProto>,
}

#[derive(Clone, PartialEq, Message)]
pub struct TensorShapeProto {
    #[prost(message, repeated, tag = "1")]
    pub dim: Vec<Dimension>,
}

/// `TensorShapeProto.Dimension` (a oneof in onnx.proto: set one of the two).
#[derive(Clone, PartialEq, Message)]
pub struct Dimension {
    #[prost(int64, optional, tag = "1")]
    pub dim_value: Option<i64>,
    #[prost(string, optional, tag = "2")]
    pub dim_param: Option<String>,
}

/// A dimension of a graph input or output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    Fixed(i64),
    /// A named dynamic dimension.
    Param(&'static str),
}

impl From<i64> for Dim {
    fn from(v: i64) -> Self {
        Dim::Fixed(v)
    }
}

pub fn attr_int(name: &str, v: i64) -> AttributeProto {
    AttributeProto {
        name: name.into(),
        i: Some(v),
        ints: vec![],
        r#type: ATTR_INT,
    }
}

pub fn attr_ints(name: &str, v: &[i64]) -> AttributeProto {
    AttributeProto {
        name: name.into(),
        i: None,
        ints: v.to_vec(),
        r#type: ATTR_INTS,
    }
}

fn value_info(name: &str, elem_type: i32, dims: &[Dim]) -> ValueInfoProto {
    ValueInfoProto {
        name: name.into(),
        r#type: Some(TypeProto {
            tensor_type: Some(TypeProtoTensor {
                elem_type,
                shape: Some(TensorShapeProto {
                    dim: dims
                        .iter()
                        .map(|d| match d {
                            Dim::Fixed(v) => Dimension {
                                dim_value: Some(*v),
                                dim_param: None,
                            },
                            Dim::Param(p) => Dimension {
                                dim_value: None,
                                dim_param: Some((*p).into()),
                            },
                        })
                        .collect(),
                }),
            }),
        }),
    }
}

/// Builds a model graph: inputs, float initializers, nodes, outputs and metadata; `build` gives
/// the serialized ModelProto (IR version 8, default-domain opset 17).
#[derive(Debug, Default, Clone)]
pub struct ModelBuilder {
    graph: GraphProto,
    metadata: Vec<StringStringEntryProto>,
}

impl ModelBuilder {
    pub fn new(name: &str) -> Self {
        Self {
            graph: GraphProto {
                name: name.into(),
                ..Default::default()
            },
            metadata: Vec::new(),
        }
    }

    pub fn input(mut self, name: &str, elem_type: i32, dims: &[Dim]) -> Self {
        self.graph.input.push(value_info(name, elem_type, dims));
        self
    }

    pub fn output(mut self, name: &str, elem_type: i32, dims: &[Dim]) -> Self {
        self.graph.output.push(value_info(name, elem_type, dims));
        self
    }

    /// A float32 constant (row-major `data` of shape `dims`).
    pub fn initializer(mut self, name: &str, dims: &[i64], data: Vec<f32>) -> Self {
        assert_eq!(
            dims.iter().product::<i64>() as usize,
            data.len(),
            "initializer {name}"
        );
        self.graph.initializer.push(TensorProto {
            dims: dims.to_vec(),
            data_type: FLOAT,
            float_data: data,
            name: name.into(),
            raw_data: vec![],
        });
        self
    }

    pub fn node(
        mut self,
        op_type: &str,
        inputs: &[&str],
        outputs: &[&str],
        attribute: Vec<AttributeProto>,
    ) -> Self {
        let name = format!("{op_type}_{}", self.graph.node.len());
        self.graph.node.push(NodeProto {
            input: inputs.iter().map(|s| s.to_string()).collect(),
            output: outputs.iter().map(|s| s.to_string()).collect(),
            name,
            op_type: op_type.into(),
            attribute,
        });
        self
    }

    /// A square `Conv` with weights `[out, in, k, k]` (row-major), bias `[out]`, stride and
    /// symmetric padding.
    #[allow(clippy::too_many_arguments)]
    pub fn conv(
        self,
        x: &str,
        y: &str,
        cin: usize,
        cout: usize,
        k: usize,
        stride: usize,
        pad: usize,
        weights: Vec<f32>,
        bias: Vec<f32>,
    ) -> Self {
        let (w, b) = (format!("{y}_w"), format!("{y}_b"));
        let (k, s, p) = (k as i64, stride as i64, pad as i64);
        self.initializer(&w, &[cout as i64, cin as i64, k, k], weights)
            .initializer(&b, &[cout as i64], bias)
            .node(
                "Conv",
                &[x, &w, &b],
                &[y],
                vec![
                    attr_ints("kernel_shape", &[k, k]),
                    attr_ints("strides", &[s, s]),
                    attr_ints("pads", &[p, p, p, p]),
                ],
            )
    }

    pub fn metadata(mut self, key: &str, value: &str) -> Self {
        self.metadata.push(StringStringEntryProto {
            key: key.into(),
            value: value.into(),
        });
        self
    }

    pub fn build(self) -> Vec<u8> {
        ModelProto {
            ir_version: 8,
            producer_name: "graspd-tests".into(),
            graph: Some(self.graph),
            opset_import: vec![OperatorSetIdProto {
                domain: String::new(),
                version: 17,
            }],
            metadata_props: self.metadata,
        }
        .encode_to_vec()
    }
}

/// A fully convolutional net `[1, cin, H, W]` → 1×1 `Conv` → `[1, cout, H', W']` with the given
/// per-output-channel weights (`weights[o]` has `cin` entries) and biases. `input_hw` /
/// `output_hw`: fixed sizes, or `None` for dynamic ones (`H`, `W` / `Ho`, `Wo`).
pub fn conv1x1_model(
    cin: usize,
    weights: &[Vec<f32>],
    bias: &[f32],
    stride: usize,
    input_hw: Option<(i64, i64)>,
    output_hw: Option<(i64, i64)>,
) -> ModelBuilder {
    let cout = weights.len();
    assert_eq!(bias.len(), cout);
    assert!(weights.iter().all(|w| w.len() == cin));
    let hw = |s: Option<(i64, i64)>, h: &'static str, w: &'static str| match s {
        Some((a, b)) => [Dim::Fixed(a), Dim::Fixed(b)],
        None => [Dim::Param(h), Dim::Param(w)],
    };
    let [ih, iw] = hw(input_hw, "H", "W");
    let [oh, ow] = hw(output_hw, "Ho", "Wo");
    ModelBuilder::new("conv1x1")
        .input(
            "image",
            FLOAT,
            &[Dim::Fixed(1), Dim::Fixed(cin as i64), ih, iw],
        )
        .conv(
            "image",
            "logits",
            cin,
            cout,
            1,
            stride,
            0,
            weights.concat(),
            bias.to_vec(),
        )
        .output(
            "logits",
            FLOAT,
            &[Dim::Fixed(1), Dim::Fixed(cout as i64), oh, ow],
        )
}

/// A deterministic pseudo-random sequence in [−a, a] (weights of [`small_fcn`]).
pub fn noise(n: usize, seed: u64, a: f32) -> Vec<f32> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * a
        })
        .collect()
}

/// A cin→16→16→6 fully convolutional net of 3 × 3 convolutions with ReLUs, pseudo-random
/// weights and dynamic H × W: the size of network architecture.md timed, for benchmarks.
pub fn small_fcn(cin: usize) -> ModelBuilder {
    let c = cin as i64;
    ModelBuilder::new("fcn")
        .input(
            "image",
            FLOAT,
            &[
                Dim::Fixed(1),
                Dim::Fixed(c),
                Dim::Param("H"),
                Dim::Param("W"),
            ],
        )
        .conv(
            "image",
            "c1",
            cin,
            16,
            3,
            1,
            1,
            noise(16 * cin * 9, 1, 0.3),
            noise(16, 2, 0.1),
        )
        .node("Relu", &["c1"], &["r1"], vec![])
        .conv(
            "r1",
            "c2",
            16,
            16,
            3,
            1,
            1,
            noise(16 * 16 * 9, 3, 0.2),
            noise(16, 4, 0.1),
        )
        .node("Relu", &["c2"], &["r2"], vec![])
        .conv(
            "r2",
            "logits",
            16,
            6,
            3,
            1,
            1,
            noise(6 * 16 * 9, 5, 0.2),
            noise(6, 6, 0.1),
        )
        .output(
            "logits",
            FLOAT,
            &[
                Dim::Fixed(1),
                Dim::Fixed(6),
                Dim::Param("H"),
                Dim::Param("W"),
            ],
        )
}

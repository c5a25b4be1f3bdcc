//! A [`DensePolicy`] as an ONNX model (IR 8, opset 17, default domain), written
//! with the small protobuf writer of `protobuf.rs`: no ONNX crate is needed for
//! the dozen node kinds used here (Sub, Mul, Clip, Slice, Gemm, Elu, Relu, Tanh,
//! Concat, Add, Max, Min, Identity). The graph computes exactly the steps of
//! `dense_policy.rs`'s header:
//!
//! `obs_history` (batch, H * obs) -> [Sub, Mul, Clip: normaliser] -> Slice the last
//! frame -> encoder Gemm/act chain -> Slice the context -> Concat -> actor chain ->
//! Clip -> `actions` (batch, act); Mul, Add, Max, Min -> `joint_targets` (batch, act).
//!
//! Field numbers are those of onnx.proto (ModelProto, GraphProto, NodeProto,
//! AttributeProto, TensorProto, ValueInfoProto, TypeProto, TensorShapeProto).

use super::dense_policy::{DenseNet, DensePolicy};
use super::protobuf::Message;
use crate::config::net::Activation;
use std::collections::BTreeMap;

/// The opset the graph is written for.
pub const OPSET: i64 = 17;
/// ONNX IR version that goes with opset 17.
const IR_VERSION: i64 = 8;
const FLOAT: i64 = 1;
const INT64: i64 = 7;

/// A graph being written: nodes and initializers in order.
struct Graph {
    nodes: Vec<Message>,
    initializers: Vec<Message>,
    counter: usize,
}

fn attribute_float(name: &str, value: f32) -> Message {
    Message::new().string(1, name).float(2, value).int(20, 1)
}

fn attribute_int(name: &str, value: i64) -> Message {
    Message::new().string(1, name).int(3, value).int(20, 2)
}

/// A float tensor value (batch, width) for the graph's inputs and outputs.
fn value_info(name: &str, width: usize) -> Message {
    let batch = Message::new().string(2, "batch");
    let width = Message::new().int(1, width as i64);
    let shape = Message::new().message(1, &batch).message(1, &width);
    let tensor_type = Message::new().int(1, FLOAT).message(2, &shape);
    Message::new().string(1, name).message(2, &Message::new().message(1, &tensor_type))
}

impl Graph {
    fn new() -> Self {
        Self { nodes: Vec::new(), initializers: Vec::new(), counter: 0 }
    }

    /// A float initializer of `dims`, named `name`.
    fn floats(&mut self, name: &str, dims: &[usize], values: &[f32]) -> String {
        let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let dims: Vec<i64> = dims.iter().map(|&d| d as i64).collect();
        self.initializers.push(Message::new().packed_ints(1, &dims).int(2, FLOAT).string(8, name).bytes(9, &raw));
        name.to_string()
    }

    /// A one-dimensional int64 initializer.
    fn ints(&mut self, name: &str, values: &[i64]) -> String {
        let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.initializers
            .push(Message::new().packed_ints(1, &[values.len() as i64]).int(2, INT64).string(8, name).bytes(9, &raw));
        name.to_string()
    }

    /// A node `op(inputs) -> output`; `output` None names it after the op and a counter.
    fn node(&mut self, op: &str, inputs: &[&str], output: Option<&str>, attributes: &[Message]) -> String {
        self.counter += 1;
        let output = output.map_or_else(|| format!("{}_{}", op.to_lowercase(), self.counter), str::to_string);
        let mut node = Message::new();
        for input in inputs {
            node = node.string(1, input);
        }
        node = node.string(2, &output).string(3, &format!("{op}_{}", self.counter)).string(4, op);
        for a in attributes {
            node = node.message(5, a);
        }
        self.nodes.push(node);
        output
    }

    /// Columns [start, end) of a (batch, width) value.
    fn columns(&mut self, x: &str, start: usize, end: usize, name: &str) -> String {
        let starts = self.ints(&format!("{name}.starts"), &[start as i64]);
        let ends = self.ints(&format!("{name}.ends"), &[end as i64]);
        let axes = self.ints(&format!("{name}.axes"), &[1]);
        self.node("Slice", &[x, &starts, &ends, &axes], Some(name), &[])
    }

    /// An MLP's Gemm and activation chain on `x`; the last layer's output is `output`.
    fn mlp(&mut self, prefix: &str, net: &DenseNet, x: &str, output: &str) -> String {
        let last = net.layers.len() - 1;
        let mut h = x.to_string();
        for (i, l) in net.layers.iter().enumerate() {
            let w = self.floats(&format!("{prefix}.{i}.weight"), &[l.outputs, l.inputs], &l.weight);
            let b = self.floats(&format!("{prefix}.{i}.bias"), &[l.outputs], &l.bias);
            let out = (i == last).then_some(output);
            h = self.node("Gemm", &[&h, &w, &b], out, &[attribute_int("transB", 1)]);
            if i < last {
                h = match net.activation {
                    Activation::Elu => self.node("Elu", &[&h], None, &[attribute_float("alpha", 1.0)]),
                    Activation::Relu => self.node("Relu", &[&h], None, &[]),
                    Activation::Tanh => self.node("Tanh", &[&h], None, &[]),
                    Activation::Identity => h,
                };
            }
        }
        h
    }
}

/// The encoded ONNX model of `policy` with `metadata` as its `metadata_props`.
pub fn onnx_model(policy: &DensePolicy, metadata: &BTreeMap<String, String>) -> Vec<u8> {
    let mut g = Graph::new();
    let (obs, history, act) = (policy.obs_dim, policy.history_len, policy.act_dim);
    let width = obs * history;
    let normalized = match &policy.normalizer {
        Some(n) => {
            let tile = |v: &[f32]| v.iter().copied().cycle().take(width).collect::<Vec<f32>>();
            let mean = g.floats("obs_normalizer.mean", &[width], &tile(&n.mean));
            let scale = g.floats("obs_normalizer.scale", &[width], &tile(&n.scale));
            let lo = g.floats("obs_normalizer.clip_min", &[], &[-n.clip]);
            let hi = g.floats("obs_normalizer.clip_max", &[], &[n.clip]);
            let centred = g.node("Sub", &["obs_history", &mean], None, &[]);
            let scaled = g.node("Mul", &[&centred, &scale], None, &[]);
            g.node("Clip", &[&scaled, &lo, &hi], Some("obs_history_normalized"), &[])
        }
        None => g.node("Identity", &["obs_history"], Some("obs_history_normalized"), &[]),
    };
    let current = g.columns(&normalized, width - obs, width, "obs_normalized");
    let actor_input = match &policy.encoder {
        Some((encoder, context)) => {
            let out = g.mlp("encoder", encoder, &normalized, "encoder_output");
            let context = g.columns(&out, 0, *context, "context");
            g.node("Concat", &[&current, &context], Some("actor_input"), &[attribute_int("axis", 1)])
        }
        None => current,
    };
    let means = g.mlp("actor", &policy.actor, &actor_input, "action_mean");
    let lo = g.floats("actions.clip_min", &[], &[-policy.clip_actions]);
    let hi = g.floats("actions.clip_max", &[], &[policy.clip_actions]);
    let actions = g.node("Clip", &[&means, &lo, &hi], Some("actions"), &[]);
    let scale = g.floats("action_scale", &[], &[policy.action_scale]);
    let pose = g.floats("default_joint_pos", &[act], &policy.default_pose);
    let lower = g.floats("joint_lower", &[act], &policy.joint_lower);
    let upper = g.floats("joint_upper", &[act], &policy.joint_upper);
    let offsets = g.node("Mul", &[&actions, &scale], None, &[]);
    let targets = g.node("Add", &[&offsets, &pose], None, &[]);
    let above = g.node("Max", &[&targets, &lower], None, &[]);
    g.node("Min", &[&above, &upper], Some("joint_targets"), &[]);

    let mut graph = Message::new();
    for n in &g.nodes {
        graph = graph.message(1, n);
    }
    graph = graph.string(2, &format!("quadcl policy, task {}", policy.task));
    for t in &g.initializers {
        graph = graph.message(5, t);
    }
    graph = graph
        .message(11, &value_info("obs_history", width))
        .message(12, &value_info("actions", act))
        .message(12, &value_info("joint_targets", act));
    let mut model = Message::new()
        .int(1, IR_VERSION)
        .string(2, "quadcl")
        .string(3, env!("CARGO_PKG_VERSION"))
        .string(6, "A quadcl policy for one task: obs_history -> actions, joint_targets (see metadata_props)")
        .message(7, &graph)
        .message(8, &Message::new().string(1, "").int(2, OPSET));
    for (key, value) in metadata {
        model = model.message(14, &Message::new().string(1, key).string(2, value));
    }
    model.encode().to_vec()
}

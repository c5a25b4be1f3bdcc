//! A [`DensePolicy`] as a safetensors file with PyTorch's key names: each
//! network an `nn.Sequential` of `nn.Linear` and activation modules
//! (`actor.0.weight`, `actor.0.bias`, `actor.2.weight`, ...: the Linear layers
//! sit at even indices, the activations between them), the normaliser and the
//! action transform as buffers. `scripts/load_exported.py` builds the module
//! these load into with `safetensors.torch.load_file`; the contract and the
//! architecture (`actor_sizes`, `actor_activation`, `encoder_sizes`,
//! `encoder_activation`, `context_dim`, `obs_clip`)
//! are in the file's metadata.

use super::dense_policy::{DenseNet, DensePolicy};
use crate::config::net::Activation;
use crate::nn::checkpoint::tensors::{f32_raw, serialize, Raw};
use std::collections::{BTreeMap, HashMap};

fn put_net(prefix: &str, net: &DenseNet, out: &mut BTreeMap<String, Raw>) {
    for (i, l) in net.layers.iter().enumerate() {
        out.insert(format!("{prefix}.{}.weight", 2 * i), f32_raw(&l.weight, vec![l.outputs, l.inputs]));
        out.insert(format!("{prefix}.{}.bias", 2 * i), f32_raw(&l.bias, vec![l.outputs]));
    }
}

fn sizes(net: &DenseNet) -> Vec<usize> {
    let mut s = vec![net.layers[0].inputs];
    s.extend(net.layers.iter().map(|l| l.outputs));
    s
}

/// PyTorch's module name for the activation.
fn activation_name(a: Activation) -> &'static str {
    match a {
        Activation::Elu => "ELU",
        Activation::Relu => "ReLU",
        Activation::Tanh => "Tanh",
        Activation::Identity => "Identity",
    }
}

/// The encoded safetensors file of `policy`, `metadata` added to its architecture keys.
pub fn safetensors_model(policy: &DensePolicy, metadata: &BTreeMap<String, String>) -> anyhow::Result<Vec<u8>> {
    let mut tensors = BTreeMap::new();
    put_net("actor", &policy.actor, &mut tensors);
    let mut meta: HashMap<String, String> = metadata.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
    meta.insert("format".into(), "pt".into());
    meta.insert("actor_activation".into(), serde_json::to_string(activation_name(policy.actor.activation))?);
    meta.insert("actor_sizes".into(), serde_json::to_string(&sizes(&policy.actor))?);
    if let Some((encoder, context)) = &policy.encoder {
        meta.insert("encoder_activation".into(), serde_json::to_string(activation_name(encoder.activation))?);
        put_net("encoder", encoder, &mut tensors);
        meta.insert("encoder_sizes".into(), serde_json::to_string(&sizes(encoder))?);
        meta.insert("context_dim".into(), context.to_string());
    }
    if let Some(n) = &policy.normalizer {
        tensors.insert("obs_normalizer.mean".into(), f32_raw(&n.mean, vec![n.mean.len()]));
        tensors.insert("obs_normalizer.scale".into(), f32_raw(&n.scale, vec![n.scale.len()]));
        meta.insert("obs_clip".into(), serde_json::to_string(&n.clip)?);
    }
    let act = policy.act_dim;
    tensors.insert("default_joint_pos".into(), f32_raw(&policy.default_pose, vec![act]));
    tensors.insert("joint_lower".into(), f32_raw(&policy.joint_lower, vec![act]));
    tensors.insert("joint_upper".into(), f32_raw(&policy.joint_upper, vec![act]));
    serialize(&tensors, Some(meta))
}

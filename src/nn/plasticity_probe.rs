//! What the plasticity diagnostics (`rl/plasticity.rs`, issue 31) read from a
//! network, without changing it or reading any random stream: its hidden layers'
//! outputs on a batch (the fused forward's own values), and per layer the
//! weights the iteration selected, with how many of them the task may still change.
//!
//! Shapes: x (batch, sizes[0]); hidden output l (batch, sizes[l + 1]), row-major.

use super::dense::DenseLayer;
use super::fused::fused_mlp_hidden;
use super::masked::var_values;
use super::mlp::FrozenWeights;
use super::network::Network;
use super::MaskedLinear;

/// One layer's selected weights in an iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectedWeights {
    /// Mean |W| over the elements the iteration's hard mask selected (masked), or over every
    /// weight of the layer (dense: a dense layer uses all of them).
    pub mean_abs: f64,
    /// The share of those elements the task's optimiser may still move: selected AND vacant for
    /// a new task of the method, PRIVATE(task) for a repeat (METHOD.md 2.5), the baselines' own
    /// update masks (PackNet: its kept vacant weights; Piggyback: none). None for a dense layer,
    /// all of whose weights train by construction.
    pub trainable_share: Option<f64>,
}

impl MaskedLinear {
    /// The iteration's selected weights (None outside a task's training, before its first
    /// mask is drawn, or when the mask selects nothing).
    pub fn selected_weights(&self) -> anyhow::Result<Option<SelectedWeights>> {
        let Some(t) = &self.training else { return Ok(None) };
        let (Some(mask), Some(update)) = (&t.mask, &t.weight_update) else { return Ok(None) };
        let mask = mask.flatten_all()?.to_vec1::<f32>()?;
        let update = update.flatten_all()?.to_vec1::<f32>()?;
        let w = var_values(&self.weight)?;
        let (mut selected, mut movable, mut abs) = (0usize, 0usize, 0.0f64);
        for ((m, u), w) in mask.iter().zip(&update).zip(&w) {
            if *m > 0.5 {
                selected += 1;
                movable += usize::from(*u > 0.5);
                abs += f64::from(w.abs());
            }
        }
        Ok((selected > 0).then(|| SelectedWeights {
            mean_abs: abs / selected as f64,
            trainable_share: Some(movable as f64 / selected as f64),
        }))
    }
}

/// Mean |W| of a dense layer (every weight counts).
fn dense_selected(layer: &DenseLayer) -> anyhow::Result<SelectedWeights> {
    let w = var_values(&layer.weight)?;
    let abs: f64 = w.iter().map(|w| f64::from(w.abs())).sum();
    Ok(SelectedWeights { mean_abs: abs / w.len().max(1) as f64, trainable_share: None })
}

impl Network {
    /// Every hidden layer's output (after the activation) of the forward with `weights` (from
    /// [`Network::frozen_weights`]) on x (batch, in): one row-major (batch, width) vector per
    /// hidden layer, input side first.
    pub fn hidden_outputs(&self, weights: &FrozenWeights, x: &candle_core::Tensor) -> anyhow::Result<Vec<Vec<f32>>> {
        anyhow::ensure!(
            weights.network() == self.name(),
            "weights of {} given to network {}",
            weights.network(),
            self.name()
        );
        fused_mlp_hidden(self.name(), self.sizes(), self.activation(), x, weights.theta())
    }

    /// Per layer, by name ("actor.l0", ...), the training iteration's selected weights: a masked
    /// network's layers with a drawn mask; a dense network's trunk layers and the head of the
    /// task in progress ("{name}.l{i}", the output layer last, as a masked network names its
    /// layers). Empty between tasks.
    pub fn selected_weights(&self) -> anyhow::Result<Vec<(String, SelectedWeights)>> {
        let mut out = Vec::new();
        match self {
            Network::Masked(n) => {
                for l in n.layers() {
                    if let Some(s) = l.selected_weights()? {
                        out.push((l.name().to_string(), s));
                    }
                }
            }
            Network::Dense(n) => {
                let Some(head) = n.current_task().and_then(|t| n.head(t)) else { return Ok(out) };
                for (i, l) in n.trunk().iter().chain(std::iter::once(head)).enumerate() {
                    out.push((format!("{}.l{i}", n.name()), dense_selected(l)?));
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::net::{Activation, MaskConfig};
    use crate::nn::{DenseMlp, MaskedMlp};
    use rand::SeedableRng;

    #[test]
    fn the_hidden_outputs_are_the_forwards_activations_layer_by_layer() {
        let cfg = MaskConfig::default();
        let mut net: Network = MaskedMlp::new("net", &[5, 7, 6, 3], Activation::Elu, &cfg, 2).unwrap().into();
        net.begin_task(0, &[]).unwrap();
        net.begin_iteration(0, &mut rand_chacha::ChaCha8Rng::seed_from_u64(1)).unwrap();
        let x = candle_core::Tensor::randn(0f32, 1.0, (9, 5), &candle_core::Device::Cpu).unwrap();
        let hidden = net.hidden_outputs(&net.frozen_weights(None).unwrap(), &x).unwrap();
        assert_eq!(hidden.iter().map(Vec::len).collect::<Vec<_>>(), vec![9 * 7, 9 * 6]);
        let mut h = x.clone();
        for (l, want) in net.as_masked().unwrap().layers().iter().zip(&hidden) {
            h = super::super::activation::activate(Activation::Elu, &l.forward(&h).unwrap()).unwrap();
            let got = h.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            for (a, b) in got.iter().zip(want) {
                assert!((a - b).abs() < 1e-4 * (1.0 + b.abs()), "{}: {a} vs {b}", l.name());
            }
        }
        let err = net.hidden_outputs(&net.frozen_weights(None).unwrap(), &x.narrow(1, 0, 4).unwrap()).unwrap_err();
        assert!(format!("{err}").contains("net: input shape [9, 4]"), "{err}");
    }

    #[test]
    fn selected_weights_count_the_iterations_mask_and_what_may_still_move() {
        let cfg = MaskConfig::default();
        let mut net: Network = MaskedMlp::new("toy", &[8, 16, 2], Activation::Elu, &cfg, 3).unwrap().into();
        assert!(net.selected_weights().unwrap().is_empty(), "nothing is selected before a task");
        net.begin_task(0, &[]).unwrap();
        net.begin_iteration(0, &mut rand_chacha::ChaCha8Rng::seed_from_u64(1)).unwrap();
        let stats = net.selected_weights().unwrap();
        assert_eq!(stats.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["toy.l0", "toy.l1"]);
        let layer = &net.as_masked().unwrap().layers()[0];
        let mask = layer.iteration_mask().unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let w = layer.weight_values().unwrap();
        let picked: Vec<f64> =
            w.iter().zip(&mask).filter(|(_, m)| **m > 0.5).map(|(w, _)| f64::from(w.abs())).collect();
        let want = picked.iter().sum::<f64>() / picked.len() as f64;
        assert!((stats[0].1.mean_abs - want).abs() < 1e-12, "{} vs {want}", stats[0].1.mean_abs);
        assert_eq!(stats[0].1.trainable_share, Some(1.0), "every element is vacant in the first task");
    }

    #[test]
    fn a_repeat_may_change_only_its_private_share_of_its_selection() {
        let cfg = MaskConfig { private_share: 0.05, ..MaskConfig::default() };
        let mut net: Network = MaskedMlp::new("toy", &[20, 16, 2], Activation::Elu, &cfg, 3).unwrap().into();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        net.begin_task(0, &[]).unwrap();
        net.begin_iteration(0, &mut rng).unwrap();
        net.end_task(&mut rng).unwrap();
        net.begin_task(0, &[]).unwrap();
        net.begin_iteration(0, &mut rng).unwrap();
        let stats = net.selected_weights().unwrap();
        let layer = &net.as_masked().unwrap().layers()[0];
        let mask = layer.task_mask(0).unwrap();
        let selected = (0..layer.states().len()).filter(|&i| mask.get(i)).count();
        let private = layer.states().iter().filter(|s| **s == crate::nn::ElementState::Private(0)).count();
        assert!(private > 0 && private < selected, "{private} private of {selected}");
        assert_eq!(stats[0].1.trainable_share, Some(private as f64 / selected as f64));
    }

    #[test]
    fn a_dense_network_reports_every_layers_mean_weight_and_no_trainable_share() {
        let mut net: Network = DenseMlp::new("toy", &[4, 6, 2], Activation::Elu, 5).unwrap().into();
        net.begin_task(0, &[]).unwrap();
        let stats = net.selected_weights().unwrap();
        assert_eq!(stats.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["toy.l0", "toy.l1"]);
        assert!(stats.iter().all(|(_, s)| s.mean_abs > 0.0 && s.trainable_share.is_none()));
    }
}

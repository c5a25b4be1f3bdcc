//! One iteration's metrics, by CleanRL-style namespaced name (`charts/*`,
//! `losses/*`, `time/*`, `plasticity/*`): the one type every training loop, the engine, the
//! methods and the observers pass around, and the names they share.

use std::collections::BTreeMap;

/// One iteration's metrics, by namespaced name (`charts/episodic_return`, `losses/approx_kl`, ...).
pub type Metrics = BTreeMap<String, f64>;

/// The metric names more than one module reads or writes.
pub mod names {
    /// Normalised performance R (METHOD.md 4): the training curve of a sequence.
    pub const PERFORMANCE: &str = "charts/performance";
    /// Mean return of the last finished episodes.
    pub const EPISODIC_RETURN: &str = "charts/episodic_return";
    /// Mean |v_xy - v_cmd| of the last finished episodes, m/s.
    pub const LIN_VEL_ERR: &str = "charts/lin_vel_err";
    /// Mean |w_z - w_cmd| of the last finished episodes, rad/s.
    pub const ANG_VEL_ERR: &str = "charts/ang_vel_err";
    /// Share of the last finished episodes that ended in a fall.
    pub const FALL_RATE: &str = "charts/fall_rate";
    /// Environment steps per second of the iteration (rollout and update).
    pub const SPS: &str = "charts/SPS";
    /// Environment steps of the training run (or of the sequence step) so far.
    pub const ENV_STEPS: &str = "charts/env_steps";
    /// Envs reset in the iteration because their physics blew up (a non-finite state, a rapier failure).
    pub const PHYSICS_RESETS: &str = "charts/physics_resets";
    /// Prefix of a masked layer's soft-score sigma, `charts/sigma/LAYER` (in `sigma_scale` units).
    pub const SIGMA: &str = "charts/sigma";
    /// Prefix of a masked layer's mean score gap at the top-k cut, `charts/score_gap/LAYER`.
    pub const SCORE_GAP: &str = "charts/score_gap";
    /// Prefix of a masked layer's mask churn, `charts/mask_churn/LAYER`: the share of the
    /// iteration's hard mask that the previous iteration had not selected.
    pub const MASK_CHURN: &str = "charts/mask_churn";
    /// Wall-clock seconds of the training run (or of the sequence step) so far.
    pub const WALL_S: &str = "time/wall_s";
    /// Prefix of every plasticity diagnostic (`rl/plasticity.rs`).
    pub const PLASTICITY: &str = "plasticity";
    /// Prefix of a network's share of dormant hidden units (ReDo), `plasticity/dormant/NET`.
    pub const DORMANT: &str = "plasticity/dormant";
    /// Prefix of the effective rank of a network's last hidden layer's features,
    /// `plasticity/effective_rank/NET`.
    pub const EFFECTIVE_RANK: &str = "plasticity/effective_rank";
    /// Prefix of a layer's mean |W| over the iteration's selected weights, `plasticity/selected_abs_w/LAYER`.
    pub const SELECTED_ABS_W: &str = "plasticity/selected_abs_w";
    /// Prefix of the share of a layer's selected weights the task may still change,
    /// `plasticity/trainable_share/LAYER` (masked layers).
    pub const TRAINABLE_SHARE: &str = "plasticity/trainable_share";
}

/// Masked layers' soft-score statistics as metrics: `charts/sigma/LAYER`,
/// `charts/score_gap/LAYER` (under `sigma_scale = "score_gap"`) and
/// `charts/mask_churn/LAYER` (from a task's second iteration).
pub fn layer_metrics(stats: &[(String, crate::nn::LayerIteration)]) -> Metrics {
    let mut m = Metrics::new();
    for (layer, s) in stats {
        m.insert(format!("{}/{layer}", names::SIGMA), s.sigma);
        if let Some(g) = s.score_gap {
            m.insert(format!("{}/{layer}", names::SCORE_GAP), g);
        }
        if let Some(c) = s.mask_churn {
            m.insert(format!("{}/{layer}", names::MASK_CHURN), c);
        }
    }
    m
}

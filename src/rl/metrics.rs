//! One iteration's metrics, by CleanRL-style namespaced name (`charts/*`,
//! `losses/*`, `time/*`): the one type every training loop, the engine, the
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
    /// Wall-clock seconds of the training run (or of the sequence step) so far.
    pub const WALL_S: &str = "time/wall_s";
}

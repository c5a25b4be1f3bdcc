//! The settings a policy acts under (issue 13's recall hazard): how an
//! observation is built and normalised and how an action becomes torques. A
//! policy evaluated or continued under other values behaves differently,
//! while its recalled weights are bit-identical, so a sequence refuses a base
//! policy trained under other values of any of them (the error names each).
//!
//! The task itself (rewards, commands, episode length, pushes, randomisation,
//! observation noise) may differ: that is what a sequence changes.

use crate::config::Config;

/// The keys (TOML paths) of every setting a trained policy depends on to act.
pub const ACTING_SETTINGS: [&str; 20] = [
    "env.urdf",
    "env.physics_dt",
    "env.decimation",
    "env.solver_iterations",
    "env.coriolis",
    "env.kp",
    "env.kd",
    "env.action_scale",
    "env.clip_actions",
    "env.default_hip_left",
    "env.default_hip_right",
    "env.default_thigh_front",
    "env.default_thigh_rear",
    "env.default_calf",
    "env.robot",
    "ppo.obs_clip",
    "ppo.normalize_observations",
    "ppo.use_cenet",
    "ppo.cenet_latent_dim",
    "ppo.cenet_logvar_clamp",
];

/// Every acting setting whose value differs between the config a policy was `trained` under
/// and the one it would run under `now`, as "key = trained value (now: value)".
pub fn acting_settings_differences(trained: &Config, now: &Config) -> Vec<String> {
    let (a, b) = (serde_json::to_value(trained).unwrap_or_default(), serde_json::to_value(now).unwrap_or_default());
    ACTING_SETTINGS
        .iter()
        .filter_map(|key| {
            let pointer = format!("/{}", key.replace('.', "/"));
            let (x, y) = (a.pointer(&pointer), b.pointer(&pointer));
            (x != y).then(|| {
                let show = |v: Option<&serde_json::Value>| v.map_or("unset".to_string(), |v| v.to_string());
                format!("{key} = {} (this run: {})", show(x), show(y))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_acting_setting_exists_and_a_change_of_one_is_named() {
        let base = Config::default();
        let json = serde_json::to_value(&base).unwrap();
        // `[env.robot]` is written only when set (the A1 has none): unset on both sides is equal.
        for key in ACTING_SETTINGS.iter().filter(|k| **k != "env.robot") {
            assert!(json.pointer(&format!("/{}", key.replace('.', "/"))).is_some(), "{key} is not a config key");
        }
        assert!(acting_settings_differences(&base, &base).is_empty());
        let mut other = base.clone();
        other.env.kp = base.env.kp + 5.0;
        other.ppo.obs_clip = 3.0;
        other.env.episode_s = 7.0; // the task, not how the policy acts
        other.env.rewards.torques = -1.0;
        let diffs = acting_settings_differences(&base, &other);
        assert_eq!(diffs.len(), 2, "{diffs:?}");
        assert!(diffs[0].starts_with("env.kp = ") && diffs[1].starts_with("ppo.obs_clip = "), "{diffs:?}");
    }
}

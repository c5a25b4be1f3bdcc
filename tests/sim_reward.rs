//! Every Table 1 reward term on a hand-made state with a known value, and
//! the weighting by the named weight and the policy dt.

use quadcl::config::EnvConfig;
use quadcl::sim::reward::{self, RewardInput, TERM_NAMES};

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-5 * (1.0 + b.abs())
}

fn state() -> RewardInput {
    let mut r = RewardInput {
        base_lin_vel: [0.8, -0.1, 0.2],
        base_ang_vel: [0.3, -0.4, 0.5],
        projected_gravity: [0.1, -0.2, -0.97],
        command: [1.0, 0.1, 0.0],
        base_height: 0.25,
        foot_height: [0.0, 0.08, 0.18, 0.03],
        foot_speed_xy: [2.0, 1.0, 0.5, 0.0],
        limb_contacts: 3,
        ..Default::default()
    };
    r.soft_lower = [-1.0; 12];
    r.soft_upper = [1.0; 12];
    r.q[0] = 1.25; // 0.25 above
    r.q[5] = -1.5; // 0.5 below
    r.torques[0] = 3.0;
    r.torques[11] = -4.0;
    r.qdd[2] = 100.0;
    r.qdd[3] = -200.0;
    r.action[0] = 1.0;
    r.last_action[0] = 0.5;
    r.action[7] = -1.0;
    r.last_action[7] = 1.0;
    r
}

#[test]
fn every_reward_term_has_its_known_value_on_a_hand_made_state() {
    let r = state();
    // |v_xy - cmd|^2 = 0.2^2 + 0.2^2 = 0.08
    assert!(close(reward::lin_vel_tracking(&r, 0.25), (-0.08f32 / 0.25).exp()));
    // (0.5 - 0)^2 = 0.25
    assert!(close(reward::ang_vel_tracking(&r, 0.25), (-1.0f32).exp()));
    assert!(close(reward::lin_vel_z(&r), 0.04));
    assert!(close(reward::ang_vel_xy(&r), 0.09 + 0.16));
    assert!(close(reward::orientation(&r), 0.01 + 0.04));
    assert!(close(reward::joint_limits(&r), 0.25 + 0.5));
    assert!(close(reward::torques(&r), 9.0 + 16.0));
    assert!(close(reward::joint_acc(&r), 10_000.0 + 40_000.0));
    assert!(close(reward::body_height(&r, 0.30), 0.0025));
    // (0-0.08)^2*2 + 0 + (0.1)^2*0.5 + (0.05)^2*0
    assert!(close(reward::feet_clearance(&r, 0.08), 0.0064 * 2.0 + 0.01 * 0.5));
    assert!(close(reward::collision(&r), 3.0));
    assert!(close(reward::action_rate(&r), 0.25 + 4.0));
}

#[test]
fn each_term_is_weight_times_value_times_policy_dt() {
    let cfg = EnvConfig::default();
    let r = state();
    let terms = reward::compute(&r, &cfg);
    let dt = cfg.physics_dt * cfg.decimation as f32;
    assert!(close(dt, 0.02), "policy at 50 Hz, dt {dt}");
    let w = &cfg.rewards;
    let expected = [
        w.lin_vel_tracking * reward::lin_vel_tracking(&r, cfg.tracking_sigma),
        w.ang_vel_tracking * reward::ang_vel_tracking(&r, cfg.tracking_sigma),
        -2.0 * 0.04,
        -0.05 * 0.25,
        -5.0 * 0.05,
        -10.0 * 0.75,
        -2e-4 * 25.0,
        -2.5e-7 * 50_000.0,
        -30.0 * 0.0025,
        -(0.0128 + 0.005),
        -3.0,
        -0.01 * 4.25,
    ];
    for (i, name) in TERM_NAMES.iter().enumerate() {
        assert!(close(terms.values[i], expected[i] * dt), "{name}: {} vs {}", terms.values[i], expected[i] * dt);
    }
    assert!(close(terms.total(), expected.iter().sum::<f32>() * dt));
}

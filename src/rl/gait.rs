//! Gait analysis: which feet touch the ground together. A policy is run with
//! a fixed command on one environment (no pushes, no randomisation), the four
//! foot contacts are recorded at every policy step (50 Hz), and the sequence
//! is summarised: duty factor per foot, touchdowns per second, how often each
//! pair of feet is in the same contact state, and the gait those pairings
//! name (trot: diagonal pairs together; pace: lateral pairs; bound: front and
//! rear pairs). What `quadcl gait` prints.

use super::agent::Agent;
use crate::config::EnvConfig;
use crate::sim::obs::PRIV_FOOT_CONTACTS;
use crate::sim::{LocomotionEnv, Perturbation, RobotModel};
use serde::{Deserialize, Serialize};

/// Foot names in contact order.
pub const FEET: [&str; 4] = ["FL", "FR", "RL", "RR"];

/// Foot pairs whose agreement is reported, and the gait each pairing stands for.
const DIAGONAL: [(usize, usize); 2] = [(0, 3), (1, 2)];
const LATERAL: [(usize, usize); 2] = [(0, 2), (1, 3)];
const FORE_AFT: [(usize, usize); 2] = [(0, 1), (2, 3)];

/// A recorded gait: the command, what the robot did, and the contact summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitReport {
    /// The command held during the recording (vx m/s, vy m/s, wz rad/s).
    pub command: [f32; 3],
    /// Seconds recorded (after the warm-up) and whether the robot fell.
    pub seconds: f32,
    pub fell: bool,
    /// Mean forward and yaw velocity over the recording (trunk heading, world yaw), m/s and rad/s.
    pub mean_vx: f32,
    pub mean_wz: f32,
    #[serde(flatten)]
    pub contacts: GaitSummary,
    /// The last two seconds as one line per foot: `#` on the ground, `.` in the air.
    pub contact_strip: Vec<String>,
}

/// Summarises a contact sequence (one `[bool; 4]` per policy step of `dt` seconds).
pub fn analyse(contacts: &[[bool; 4]], dt: f32) -> GaitSummary {
    let n = contacts.len().max(1) as f32;
    let mut duty = [0.0f32; 4];
    let mut touchdowns = [0.0f32; 4];
    for (k, c) in contacts.iter().enumerate() {
        for f in 0..4 {
            duty[f] += f32::from(u8::from(c[f])) / n;
            if k > 0 && c[f] && !contacts[k - 1][f] {
                touchdowns[f] += 1.0;
            }
        }
    }
    let seconds = contacts.len() as f32 * dt;
    let touchdowns_per_s = touchdowns.map(|t| if seconds > 0.0 { t / seconds } else { 0.0 });
    let agreement = |pairs: &[(usize, usize); 2]| -> f32 {
        let same = contacts.iter().map(|c| pairs.iter().filter(|(a, b)| c[*a] == c[*b]).count()).sum::<usize>();
        same as f32 / (2.0 * n)
    };
    let (diagonal, lateral, fore_aft) = (agreement(&DIAGONAL), agreement(&LATERAL), agreement(&FORE_AFT));
    let gait = classify(&duty, diagonal, lateral, fore_aft);
    GaitSummary {
        duty_factor: duty,
        touchdowns_per_s,
        diagonal_agreement: diagonal,
        lateral_agreement: lateral,
        fore_aft_agreement: fore_aft,
        gait,
    }
}

/// What the contact analysis finds in a contact sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitSummary {
    /// Fraction of steps each foot (FL, FR, RL, RR) is on the ground.
    pub duty_factor: [f32; 4],
    /// Touchdowns per second per foot.
    pub touchdowns_per_s: [f32; 4],
    /// Fraction of steps the two feet of a pair are in the same state, for the
    /// diagonal (FL-RR, FR-RL), lateral (FL-RL, FR-RR) and fore-aft (FL-FR, RL-RR) pairs.
    pub diagonal_agreement: f32,
    pub lateral_agreement: f32,
    pub fore_aft_agreement: f32,
    /// `trot`, `pace`, `bound`, `stand` (every foot down nearly always) or `irregular`.
    pub gait: String,
}

/// A gait is named when one pairing agrees at least 80 % of the time and clearly more than the
/// other two; feet that stay down over 90 % of the time are `stand`.
fn classify(duty: &[f32; 4], diagonal: f32, lateral: f32, fore_aft: f32) -> String {
    if duty.iter().all(|d| *d > 0.9) {
        return "stand".into();
    }
    let named = [("trot", diagonal), ("pace", lateral), ("bound", fore_aft)];
    let (name, best) = named.iter().fold(("irregular", 0.0f32), |acc, (n, a)| if *a > acc.1 { (n, *a) } else { acc });
    let runner_up = named.iter().filter(|(n, _)| *n != name).map(|(_, a)| *a).fold(0.0f32, f32::max);
    if best >= 0.8 && best - runner_up >= 0.2 {
        name.into()
    } else {
        "irregular".into()
    }
}

/// One line per foot of the last `steps` steps: `#` on the ground, `.` in the air.
pub fn contact_strip(contacts: &[[bool; 4]], steps: usize) -> Vec<String> {
    let tail = &contacts[contacts.len().saturating_sub(steps)..];
    (0..4)
        .map(|f| format!("{} {}", FEET[f], tail.iter().map(|c| if c[f] { '#' } else { '.' }).collect::<String>()))
        .collect()
}

/// One held command and how long to watch it (`quadcl gait`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldCommand {
    /// (vx m/s, vy m/s, wz rad/s), held for the whole run.
    pub command: [f32; 3],
    /// Seconds to settle into the gait before recording.
    pub warmup_s: f32,
    /// Seconds recorded and analysed.
    pub seconds: f32,
    /// Seed of the environment's reset.
    pub seed: u64,
}

/// Runs `agent`'s deterministic policy on one environment of `task` with the
/// command of `run` held for `warmup_s + seconds` (no pushes, nominal physics)
/// and analyses the last `seconds`.
pub fn record_gait(
    agent: &Agent,
    env_cfg: &EnvConfig,
    robot: &RobotModel,
    task: &Perturbation,
    run: HeldCommand,
) -> anyhow::Result<GaitReport> {
    let HeldCommand { command, warmup_s, seconds, seed } = run;
    let cfg = EnvConfig { randomize: false, push_interval_s: 0.0, ..env_cfg.clone() };
    let mut env = LocomotionEnv::new(&cfg, robot, task)?;
    env.reset(seed)?;
    env.set_command(command);
    let dt = cfg.policy_dt();
    let warmup = (warmup_s / dt).round() as usize;
    let total = warmup + (seconds / dt).round() as usize;
    let (mut contacts, mut vx, mut wz, mut fell) = (Vec::new(), 0.0f32, 0.0f32, false);
    // Nothing trains while the gait is recorded: the effective weights are made once.
    let weights = agent.acting_weights()?;
    for k in 0..total {
        let actions = agent.act_deterministic_with(&weights, env.observation(), env.obs_history())?;
        let step = env.step(&actions)?;
        if step.terminated {
            fell = true;
            break;
        }
        // Hold the command through the env's own resampling.
        if env.command() != command {
            env.set_command(command);
        }
        if k >= warmup {
            let p = env.privileged_observation();
            contacts.push(std::array::from_fn(|f| p[PRIV_FOOT_CONTACTS + f] > 0.5));
            let s = env.raw_state();
            vx += trunk_forward_speed(s);
            wz += s.base_ang_vel[2];
        }
    }
    let n = contacts.len().max(1) as f32;
    Ok(GaitReport {
        command,
        seconds: contacts.len() as f32 * dt,
        fell,
        mean_vx: vx / n,
        mean_wz: wz / n,
        contacts: analyse(&contacts, dt),
        contact_strip: contact_strip(&contacts, (2.0 / dt).round() as usize),
    })
}

/// The world-frame velocity projected on the trunk's heading (its x axis in the ground plane).
fn trunk_forward_speed(s: &crate::sim::RawState) -> f32 {
    let [x, y, z, w] = s.base_quat;
    // First column of the rotation matrix: the trunk's x axis in the world frame.
    let (hx, hy) = (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z));
    let norm = (hx * hx + hy * hy).sqrt().max(1e-6);
    (s.base_lin_vel[0] * hx + s.base_lin_vel[1] * hy) / norm
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `period` steps per cycle, feet down in the first half of their phase.
    fn pattern(phases: [usize; 4], period: usize, steps: usize) -> Vec<[bool; 4]> {
        (0..steps).map(|k| std::array::from_fn(|f| (k + phases[f]) % period < period / 2)).collect()
    }

    #[test]
    fn diagonal_pairs_in_phase_are_a_trot() {
        // FL and RR together, FR and RL half a cycle later: 2 touchdowns per second at 50 Hz.
        let s = analyse(&pattern([0, 12, 12, 0], 25, 500), 0.02);
        assert_eq!(s.gait, "trot");
        assert_eq!(s.diagonal_agreement, 1.0);
        assert!(s.lateral_agreement < 0.1 && s.fore_aft_agreement < 0.1, "{s:?}");
        for f in 0..4 {
            assert!((s.duty_factor[f] - 0.48).abs() < 0.02, "{s:?}");
            assert!((s.touchdowns_per_s[f] - 2.0).abs() < 0.11, "{s:?}");
        }
    }

    #[test]
    fn lateral_and_fore_aft_pairs_are_pace_and_bound() {
        assert_eq!(analyse(&pattern([0, 12, 0, 12], 25, 500), 0.02).gait, "pace");
        assert_eq!(analyse(&pattern([0, 0, 12, 12], 25, 500), 0.02).gait, "bound");
    }

    #[test]
    fn feet_that_never_lift_stand_and_unrelated_phases_are_irregular() {
        assert_eq!(analyse(&vec![[true; 4]; 100], 0.02).gait, "stand");
        // Quarter-cycle offsets (a lateral-sequence walk): no pair agrees 80 % of the time.
        assert_eq!(analyse(&pattern([0, 12, 6, 18], 25, 500), 0.02).gait, "irregular");
    }

    #[test]
    fn the_strip_shows_the_last_steps_of_each_foot() {
        let strip =
            contact_strip(&[[true, false, true, false], [false, true, true, false], [true, true, false, false]], 2);
        assert_eq!(strip, vec!["FL .#", "FR ##", "RL #.", "RR .."]);
    }
}

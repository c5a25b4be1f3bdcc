//! What every training loop shares in how it reports and counts: `quadcl
//! train` (`rl::trainer`), a sequence (`engine::Session`, shown by
//! `headless`) and sim-to-real fine-tuning (`engine::sim2real`) draw the same
//! progress bar, summarise an iteration in the same words, and stamp the same
//! counters on its metrics ([`TrainingClock`]: `charts/env_steps`, `time/wall_s`).

use super::metrics::{names, Metrics};
use indicatif::{ProgressBar, ProgressStyle};
use std::time::Instant;

/// A progress bar on stderr over `len` iterations (hidden when `visible` is
/// false, e.g. without a terminal); its prefix names what trains.
pub fn progress_bar(len: usize, visible: bool) -> ProgressBar {
    let bar = if visible { ProgressBar::new(len as u64) } else { ProgressBar::hidden() };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} {prefix} [{bar:30}] {pos}/{len} it  eta {eta}  {msg}")
            .expect("a valid progress template")
            .progress_chars("=> "),
    );
    bar
}

/// One iteration in words: `return 3.21 lin_vel_err 0.410 ang_vel_err 0.620 fall_rate 0.20 SPS 3300`
/// (`-` for a figure the iteration did not report, e.g. before any episode ended),
/// then `physics_resets N` when envs were reset after a physics blow-up.
pub fn iteration_summary(metrics: &Metrics) -> String {
    let mut line = String::new();
    for (label, key, digits) in [
        ("return", names::EPISODIC_RETURN, 2),
        ("lin_vel_err", names::LIN_VEL_ERR, 3),
        ("ang_vel_err", names::ANG_VEL_ERR, 3),
        ("fall_rate", names::FALL_RATE, 2),
        ("SPS", names::SPS, 0),
    ] {
        if !line.is_empty() {
            line.push(' ');
        }
        match metrics.get(key) {
            Some(v) => line.push_str(&format!("{label} {v:.digits$}")),
            None => line.push_str(&format!("{label} -")),
        }
    }
    // Only when it happened: a blow-up is rare and worth seeing.
    if let Some(&resets) = metrics.get(names::PHYSICS_RESETS).filter(|&&r| r > 0.0) {
        line.push_str(&format!(" physics_resets {resets:.0}"));
    }
    line
}

/// The echo line of iteration `iteration` (1-based) of `iterations` of step `step`:
/// `step 0 iteration 25/500: return 3.21 lin_vel_err 0.410 ...` (see [`iteration_summary`]).
pub fn iteration_line(step: usize, iteration: usize, iterations: usize, metrics: &Metrics) -> String {
    format!("step {step} iteration {iteration}/{iterations}: {}", iteration_summary(metrics))
}

/// Environment steps and wall-clock seconds of one training run so far,
/// stamped on each iteration's metrics as `charts/env_steps` and `time/wall_s`.
/// A resumed run starts from the counts it had reached.
#[derive(Debug, Clone)]
pub struct TrainingClock {
    env_steps: usize,
    wall_before: f64,
    start: Instant,
}

impl TrainingClock {
    /// A clock that has already counted `env_steps` steps and `wall_s` seconds.
    pub fn new(env_steps: usize, wall_s: f64) -> Self {
        Self { env_steps, wall_before: wall_s, start: Instant::now() }
    }

    /// Counts an iteration of `env_steps` steps and stamps the totals on `metrics`.
    pub fn stamp(&mut self, metrics: &mut Metrics, env_steps: usize) {
        self.env_steps += env_steps;
        metrics.insert(names::ENV_STEPS.into(), self.env_steps as f64);
        metrics.insert(names::WALL_S.into(), self.wall_s());
    }

    /// Environment steps so far.
    pub fn env_steps(&self) -> usize {
        self.env_steps
    }

    /// Wall-clock seconds so far.
    pub fn wall_s(&self) -> f64 {
        self.wall_before + self.start.elapsed().as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_iteration_line_names_step_and_iteration() {
        let metrics =
            [("charts/episodic_return".to_string(), 3.214), ("charts/SPS".to_string(), 3301.7)].into_iter().collect();
        assert_eq!(
            iteration_line(1, 25, 500, &metrics),
            "step 1 iteration 25/500: return 3.21 lin_vel_err - ang_vel_err - fall_rate - SPS 3302"
        );
    }

    #[test]
    fn physics_resets_join_the_line_only_when_there_were_some() {
        let mut metrics: Metrics = [(names::PHYSICS_RESETS.to_string(), 0.0)].into_iter().collect();
        assert!(!iteration_summary(&metrics).contains("physics"));
        metrics.insert(names::PHYSICS_RESETS.into(), 2.0);
        assert!(iteration_summary(&metrics).ends_with("SPS - physics_resets 2"), "{}", iteration_summary(&metrics));
    }

    #[test]
    fn the_iteration_summary_shows_missing_figures_as_a_dash() {
        let metrics =
            [(names::EPISODIC_RETURN.to_string(), 3.214), (names::SPS.to_string(), 3301.7)].into_iter().collect();
        assert_eq!(iteration_summary(&metrics), "return 3.21 lin_vel_err - ang_vel_err - fall_rate - SPS 3302");
    }

    #[test]
    fn the_clock_counts_on_from_where_a_resumed_run_stopped() {
        let mut clock = TrainingClock::new(100, 5.0);
        let mut m = Metrics::new();
        clock.stamp(&mut m, 24);
        clock.stamp(&mut m, 24);
        assert_eq!(m[names::ENV_STEPS], 148.0);
        assert!(m[names::WALL_S] >= 5.0);
    }
}

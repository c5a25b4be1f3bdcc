//! What the recording tests share: the shipped base policy, the options of a
//! short walk under a held command, and a probe that keeps what the simulator
//! reported at every reset and step (to compare a file with).
#![allow(dead_code)]

use quadcl::record::RecordOptions;
use quadcl::sim::{StepInfo, StepObserver};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

pub fn base() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/base-a1-flat")
}

/// `seconds` of walking at 0.5 m/s forward from the reset of seed 3.
pub fn options(seconds: f64) -> RecordOptions {
    RecordOptions { seconds, episodes: None, command: Some([0.5, 0.0, 0.0]), seed: 3, force: false }
}

/// (sim time, joint angles, trunk height) of every reset and step.
pub type Seen = Arc<Mutex<Vec<(f64, [f32; 12], f32)>>>;

/// Keeps what the simulator reported at every reset and step.
pub struct Probe(pub Seen);

impl StepObserver for Probe {
    fn on_reset(&mut self, info: &StepInfo) {
        self.on_step(info);
    }
    fn on_step(&mut self, info: &StepInfo) {
        self.0.lock().unwrap().push((info.sim_time, info.state.q, info.state.base_pos[2]));
    }
}

/// What the simulator reports over `steps` control steps of [`options`]' walk, observed directly.
pub fn walk_seen(steps: usize) -> Vec<(f64, [f32; 12], f32)> {
    let seen: Seen = Arc::new(Mutex::new(Vec::new()));
    let mut viewer = quadcl::rl::RobotViewer::new(&base(), "none", 3, Some([0.5, 0.0, 0.0])).unwrap();
    viewer.observe(Box::new(Probe(seen.clone())));
    for _ in 0..steps {
        viewer.step().unwrap();
    }
    let seen = seen.lock().unwrap().clone();
    seen
}

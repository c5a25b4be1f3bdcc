//! `train --resume` is exact: a training of the simulated robot that crashes
//! mid-iteration and is resumed from its last checkpoint ends with the same
//! policy, the same checkpoint and the same metrics (timing fields aside) as
//! one that never stopped. And a damaged training state is an error that
//! names the file, not a silently different run.

use quadcl::config::{Config, EnvConfig, PpoConfig};
use quadcl::rl::{load_resume_point, train_from, EnvDims, EpisodeReplay, SimTrainEnv, TrainEnv, VecStep};
use quadcl::sim::Perturbation;
use std::path::Path;

/// Tiny networks on 4 robots; short episodes and frequent pushes, so that
/// checkpoints fall mid-episode, after resets, and after the env's own pushes.
fn config(iterations: usize) -> Config {
    let mut cfg = Config {
        seed: 3,
        env: EnvConfig { episode_s: 0.5, push_interval_s: 0.2, ..EnvConfig::default() },
        ppo: PpoConfig {
            num_envs: 4,
            steps_per_env: 16,
            iterations,
            checkpoint_every: 2,
            cenet_decoder_hidden: vec![8],
            cenet_latent_dim: 2,
            ..PpoConfig::default()
        },
        ..Config::default()
    };
    cfg.net.actor.hidden = vec![16];
    cfg.net.critic.hidden = vec![16];
    cfg.net.cenet.hidden = vec![8];
    // The entropy phase ends before the checkpoint the crash resumes from (ln sigma stops training).
    cfg.net.mask.entropy_iterations = Some(3);
    cfg
}

/// The simulated batch, failing (as a crash would) after `fail_after` steps.
struct Crashing {
    inner: SimTrainEnv,
    steps_left: usize,
}

impl TrainEnv for Crashing {
    fn dims(&self) -> EnvDims {
        self.inner.dims()
    }
    fn num_envs(&self) -> usize {
        self.inner.num_envs()
    }
    fn observations(&self) -> &[f32] {
        self.inner.observations()
    }
    fn privileged_observations(&self) -> &[f32] {
        self.inner.privileged_observations()
    }
    fn obs_histories(&self) -> &[f32] {
        self.inner.obs_histories()
    }
    fn step(&mut self, actions: &[f32]) -> anyhow::Result<VecStep> {
        anyhow::ensure!(self.steps_left > 0, "crashed");
        self.steps_left -= 1;
        self.inner.step(actions)
    }
    fn keep_replays(&mut self) -> anyhow::Result<bool> {
        self.inner.keep_replays()
    }
    fn replays(&self) -> anyhow::Result<Option<Vec<EpisodeReplay>>> {
        self.inner.replays()
    }
    fn restore(&mut self, replays: &[EpisodeReplay]) -> anyhow::Result<()> {
        self.inner.restore(replays)
    }
}

fn sim_env(cfg: &Config) -> SimTrainEnv {
    SimTrainEnv::new(&cfg.env, &Perturbation::none(), cfg.ppo.num_envs, cfg.seed).unwrap()
}

/// metrics.jsonl without the fields that measure time.
fn untimed_rows(dir: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    text.lines()
        .map(|l| {
            let mut row: serde_json::Map<String, serde_json::Value> = serde_json::from_str(l).unwrap();
            row.retain(|k, _| !k.starts_with("time/") && k != quadcl::rl::metric_names::SPS);
            serde_json::Value::Object(row)
        })
        .collect()
}

/// Every file of `dir` (one level), by name, except `skip`.
fn files(dir: &Path, skip: &[&str]) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .map(|e| (e.file_name().to_string_lossy().into_owned(), e.path()))
        .filter(|(name, _)| !skip.contains(&name.as_str()))
        .map(|(name, path)| (name, std::fs::read(path).unwrap()))
        .collect();
    out.sort();
    out
}

#[test]
fn a_training_crashed_mid_iteration_and_resumed_ends_as_one_that_never_stopped() {
    let cfg = config(7);
    let reference = tempfile::tempdir().unwrap();
    train_from(&cfg, "none", &mut sim_env(&cfg), reference.path(), false, true, None).unwrap();

    let dir = tempfile::tempdir().unwrap();
    // Crashes in iteration 6 (16 steps an iteration): the checkpoint of iteration 4 is the last.
    let mut crashing = Crashing { inner: sim_env(&cfg), steps_left: 5 * 16 + 9 };
    let err = train_from(&cfg, "none", &mut crashing, dir.path(), false, true, None).unwrap_err();
    assert!(format!("{err:#}").contains("crashed"), "{err:#}");
    assert_eq!(untimed_rows(dir.path()).len(), 5, "every finished iteration has its row on disk");

    let point = load_resume_point(&cfg, "none", dir.path()).unwrap();
    assert_eq!(point.state.iteration, 4);
    assert!(point.is_exact());
    // The environments as a new process builds them: the replays put them where they were.
    train_from(&cfg, "none", &mut sim_env(&cfg), dir.path(), false, true, Some(point)).unwrap();

    let (resumed, never_stopped) = (untimed_rows(dir.path()), untimed_rows(reference.path()));
    assert_eq!(resumed.len(), never_stopped.len());
    for (i, (a, b)) in resumed.iter().zip(&never_stopped).enumerate() {
        let differ: Vec<&String> =
            b.as_object().unwrap().iter().filter(|(k, v)| a.get(k.as_str()) != Some(v)).map(|(k, _)| k).collect();
        assert!(differ.is_empty() && a == b, "iteration {}: {differ:?} differ", i + 1);
    }
    let policy = |d: &Path| files(&d.join("policy"), &[]);
    assert_eq!(policy(dir.path()), policy(reference.path()), "policy files byte for byte");
    let checkpoint = |d: &Path| files(&d.join("checkpoint"), &["trainer.json"]);
    assert_eq!(checkpoint(dir.path()), checkpoint(reference.path()), "last checkpoint byte for byte");
}

#[test]
fn a_damaged_training_state_is_an_error_naming_the_file_and_the_run_is_kept() {
    let cfg = config(2);
    let dir = tempfile::tempdir().unwrap();
    train_from(&cfg, "none", &mut sim_env(&cfg), dir.path(), false, true, None).unwrap();
    let path = dir.path().join("checkpoint").join(quadcl::rl::TRAINING_STATE_FILE);
    let good = std::fs::read(&path).unwrap();
    let policy_before = files(&dir.path().join("policy"), &[]);

    // Cut short, and garbage.
    for bad in [good[..good.len() / 2].to_vec(), b"not a tensor file".to_vec(), Vec::new()] {
        std::fs::write(&path, &bad).unwrap();
        let err = format!("{:#}", load_resume_point(&config(4), "none", dir.path()).unwrap_err());
        assert!(err.contains("training_state.safetensors"), "{err}");
    }
    // A state that fits another batch of envs: refused when it is restored, naming the checkpoint.
    let wider = {
        let mut c = config(2);
        c.ppo.num_envs = 6;
        c
    };
    let other = tempfile::tempdir().unwrap();
    train_from(&wider, "none", &mut sim_env(&wider), other.path(), false, true, None).unwrap();
    std::fs::copy(other.path().join("checkpoint").join(quadcl::rl::TRAINING_STATE_FILE), &path).unwrap();
    let err = format!("{:#}", load_resume_point(&config(4), "none", dir.path()).unwrap_err());
    assert!(err.contains("does not match the digest in trainer.json"), "{err}");
    // Even with the digest made to fit, the state does not fit this run's batch.
    let trainer = dir.path().join("checkpoint").join("trainer.json");
    let mut state: serde_json::Value = serde_json::from_slice(&std::fs::read(&trainer).unwrap()).unwrap();
    state["training_state_sha256"] = quadcl::util::sha256_hex(&std::fs::read(&path).unwrap()).into();
    std::fs::write(&trainer, serde_json::to_string(&state).unwrap()).unwrap();
    let point = load_resume_point(&config(4), "none", dir.path()).unwrap();
    let err = train_from(&config(4), "none", &mut sim_env(&cfg), dir.path(), false, true, Some(point)).unwrap_err();
    let err = format!("{err:#}");
    assert!(err.contains("checkpoint") && err.contains("6 env replays for a batch of 4"), "{err}");
    assert_eq!(files(&dir.path().join("policy"), &[]), policy_before, "the finished policy is untouched");
}

//! `quadcl train --resume`: a run interrupted after a checkpoint goes on from
//! it, and a checkpoint that does not match is a clear error that leaves the
//! files as they were; settings that act only at the end of the task may
//! differ.

use candle_core::Tensor;
use quadcl::config::{Config, PpoConfig};
use quadcl::nn::ElementState;
use quadcl::rl::{load_policy, load_resume_point, train_from, ToyEnv};
use quadcl::util::{derive_seed, Stream};

fn toy_config(iterations: usize) -> Config {
    let mut cfg = Config {
        seed: 9,
        ppo: PpoConfig {
            num_envs: 16,
            steps_per_env: 8,
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
    cfg
}

fn metric_rows(dir: &std::path::Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    text.lines().map(|l| serde_json::from_str(l).unwrap()).collect()
}

/// Resumes the run in `dir` with `cfg` and trains it to `cfg.ppo.iterations`.
fn resume(cfg: &Config, dir: &std::path::Path) -> quadcl::rl::TrainSummary {
    let point = load_resume_point(cfg, "none", dir).unwrap();
    let mut env = ToyEnv::new(16, 10, derive_seed(cfg.seed, Stream::Trainer(point.state.iteration)));
    train_from(cfg, "none", &mut env, dir, false, true, Some(point)).unwrap()
}

#[test]
fn a_resumed_run_goes_on_from_its_last_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    // Stopped after 5 iterations (checkpoints at 2, 4 and the last, 5), then
    // the 5th row and checkpoint dropped as if interrupted after the 4th.
    let first = toy_config(4);
    let mut env = ToyEnv::new(16, 10, first.seed);
    train_from(&first, "none", &mut env, dir.path(), false, true, None).unwrap();
    let before = metric_rows(dir.path());
    assert_eq!(before.len(), 4);

    let longer = toy_config(8);
    let point = load_resume_point(&longer, "none", dir.path()).unwrap();
    assert_eq!(point.state.iteration, 4);
    let agent = &point.agent;
    assert!(!agent.in_recall() && agent.actor().current_task() == Some(0), "the task must still be in training");
    assert!(!point.is_exact(), "the toy environments keep no replays");
    let mut env = ToyEnv::new(16, 10, derive_seed(longer.seed, Stream::Trainer(point.state.iteration)));
    let summary = train_from(&longer, "none", &mut env, dir.path(), false, true, Some(point)).unwrap();
    assert_eq!(summary.iterations, 8);

    let after = metric_rows(dir.path());
    assert_eq!(after.len(), 8, "rows after the checkpoint are replaced, not duplicated");
    assert_eq!(after[..4], before[..4], "rows up to the checkpoint are kept as they were");
    let iterations: Vec<f64> = after.iter().map(|r| r["charts/iteration"].as_f64().unwrap()).collect();
    assert_eq!(iterations, (1..=8).map(f64::from).collect::<Vec<_>>());
    // tb/ reads back as the rows: step = iteration, the resumed file restarting at iteration 5.
    let files = quadcl::log::read_dir_scalars(&dir.path().join("tb")).unwrap();
    assert_eq!(files.iter().map(|f| f.session_starts.clone()).collect::<Vec<_>>(), vec![vec![], vec![5]]);
    let kept: Vec<(i64, f32)> = files
        .iter()
        .enumerate()
        .flat_map(|(i, f)| f.scalars.iter().filter(move |(s, _, _)| i == 1 || *s < 5).map(|(s, t, v)| (*s, t, *v)))
        .filter(|(_, t, _)| *t == "charts/iteration")
        .map(|(s, _, v)| (s, v))
        .collect();
    assert_eq!(kept, (1..=8).map(|i| (i, i as f32)).collect::<Vec<_>>());
    assert!(dir.path().join("policy").join("manifest.json").is_file());
    assert!(!dir.path().join("checkpoint.new").exists() && !dir.path().join("checkpoint.old").exists());
}

#[test]
fn resuming_with_another_config_or_task_is_an_error_that_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(3);
    let mut env = ToyEnv::new(16, 10, cfg.seed);
    train_from(&cfg, "none", &mut env, dir.path(), false, true, None).unwrap();
    let snapshot = std::fs::read(dir.path().join("checkpoint").join("model.safetensors")).unwrap();

    let mut other = toy_config(6);
    other.ppo.entropy_coef = 0.5;
    let err = format!("{:#}", load_resume_point(&other, "none", dir.path()).unwrap_err());
    assert!(err.contains("checkpoint") && err.contains("another configuration"), "{err}");
    let err = format!("{:#}", load_resume_point(&toy_config(6), "crash:FL", dir.path()).unwrap_err());
    assert!(err.contains("not \"crash:FL\""), "{err}");

    std::fs::write(dir.path().join("checkpoint").join("trainer.json"), "{ not json").unwrap();
    let err = format!("{:#}", load_resume_point(&toy_config(6), "none", dir.path()).unwrap_err());
    assert!(err.contains("trainer.json"), "{err}");
    assert_eq!(std::fs::read(dir.path().join("checkpoint").join("model.safetensors")).unwrap(), snapshot);

    let finished = format!("{:#}", quadcl::rl::load_training_checkpoint(&dir.path().join("policy")).unwrap_err());
    assert!(finished.contains("not a checkpoint of a run in progress"), "{finished}");
}

#[test]
fn ending_a_task_at_its_checkpoint_drops_later_rows_and_keeps_the_time_splits() {
    // Interrupted after writing the row of iteration 5 but before its checkpoint:
    // resuming with --iterations 4 only ends the task at the checkpoint.
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(4);
    let mut env = ToyEnv::new(16, 10, cfg.seed);
    train_from(&cfg, "none", &mut env, dir.path(), false, true, None).unwrap();
    let rows = metric_rows(dir.path());
    let path = dir.path().join("metrics.jsonl");
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str(
        &serde_json::to_string(&rows[3]).unwrap().replace("\"charts/iteration\":4.0", "\"charts/iteration\":5.0"),
    );
    text.push('\n');
    std::fs::write(&path, text).unwrap();
    assert_eq!(metric_rows(dir.path()).len(), 5);

    let summary = resume(&cfg, dir.path());
    assert_eq!(metric_rows(dir.path()), rows, "the row past the checkpoint is dropped");
    let sum = |key: &str| rows.iter().map(|r| r[key].as_f64().unwrap()).sum::<f64>();
    assert_eq!(summary.update_s, sum("time/update_s"));
    assert_eq!(summary.env_s, sum("time/env_s"));
    assert!(summary.update_s > 0.0);
}

#[test]
fn a_finished_run_may_be_ended_again_with_other_end_of_task_settings_only() {
    // The private share and re-initialisation act only when the task ends (METHOD.md 2.4):
    // ending the same checkpoint with p = 0 gives the same task (masks, recall) with no
    // private element; any other change is still refused.
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(4);
    let mut env = ToyEnv::new(16, 10, cfg.seed);
    train_from(&cfg, "none", &mut env, dir.path(), false, true, None).unwrap();
    let first = load_policy(&dir.path().join("policy"), None).unwrap();

    let mut shared = toy_config(4);
    (shared.net.mask.private_share, shared.net.mask.reinit_scale) = (0.0, 0.1);
    let mut wider = shared.clone();
    wider.net.mask.capacity = 0.3;
    let err = format!("{:#}", load_resume_point(&wider, "none", dir.path()).unwrap_err());
    assert!(err.contains("another configuration"), "{err}");

    resume(&shared, dir.path());
    let ended = load_policy(&dir.path().join("policy"), None).unwrap();

    let private = |p: &quadcl::rl::LoadedPolicy| -> usize {
        p.agent
            .masked_networks()
            .into_iter()
            .flat_map(|n| n.layers())
            .map(|l| l.states().iter().filter(|s| matches!(s, ElementState::Private(_))).count())
            .sum()
    };
    assert!(private(&first) > 0, "the default p = 0.02 made some elements private");
    assert_eq!(private(&ended), 0);
    let x =
        Tensor::ones((3, first.agent.actor().sizes()[0]), candle_core::DType::F32, &candle_core::Device::Cpu).unwrap();
    let out = |p: &quadcl::rl::LoadedPolicy| {
        p.agent.actor().forward_task(0, &x).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap()
    };
    assert_eq!(out(&first), out(&ended), "the task's recall is unchanged");
    for (a, b) in first.agent.masked_networks().into_iter().zip(ended.agent.masked_networks()) {
        for (la, lb) in a.layers().iter().zip(b.layers()) {
            assert_eq!(la.task_mask(0), lb.task_mask(0), "{}", la.name());
        }
    }
}

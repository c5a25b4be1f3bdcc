//! `scenes/smoke.toml` end to end with the real PPO learner on the simulated
//! quadruped: every metrics.json field, forgetting exactly 0.0, and every
//! earlier task's evaluation after the last task bit-identical to its
//! evaluation right after it was learned (nn's exact recall + deterministic
//! evaluation); resume gives the same file byte for byte.

mod engine_common;
use engine_common::assert_metrics_json_complete;
use quadcl::headless::{run, RunOptions};
use quadcl::record::RecordFormat;
use std::path::Path;

fn smoke() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml")
}

#[test]
fn smoke_run_forgets_nothing_and_recalls_every_task_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("smoke");
    let m = run(&smoke(), &out, RunOptions::default()).unwrap();
    assert_eq!(m.completed_steps, 3);
    assert_eq!(m.summary.forgetting, Some(0.0));
    assert_metrics_json_complete(&out);
    for (j, name) in m.tasks.iter().enumerate().take(2) {
        let right_after = m.evaluations[j].iter().find(|e| &e.report.task == name).unwrap();
        let at_end = m.evaluations[2].iter().find(|e| &e.report.task == name).unwrap();
        assert_eq!(right_after, at_end, "{name}");
    }
    for curve in &m.curves {
        assert_eq!(curve.performance.len(), 3, "one training-curve value per iteration");
    }
    // The last checkpoint is a policy directory `quadcl eval` reads, for every task.
    let last = out.join("checkpoints/step-02-noise_FR");
    for name in &m.tasks {
        let loaded = quadcl::rl::load_policy(&last, Some(name)).unwrap();
        assert_eq!(&loaded.tasks, &m.tasks);
    }
    // An earlier one names every task of the sequence but has learned only the first.
    let first = out.join("checkpoints/step-00-crash_FL");
    assert_eq!(quadcl::rl::load_policy(&first, None).unwrap().agent.task(), 0, "its last learned task");
    let err = format!("{:#}", quadcl::rl::load_policy(&first, Some("noise:FR")).unwrap_err());
    assert!(err.contains("step-00-crash_FL") && err.contains("not learned yet") && err.contains("crash:FL"), "{err}");
    let zero_shot = quadcl::rl::load_for_task(&first, "noise:FR").unwrap();
    assert_eq!(zero_shot.agent.task(), 0, "eval on a task to come runs the last learned one");

    let parts = tmp.path().join("parts");
    run(&smoke(), &parts, RunOptions { stop_after: Some(2), ..Default::default() }).unwrap();
    run(&smoke(), &parts, RunOptions { resume: true, ..Default::default() }).unwrap();
    assert_eq!(std::fs::read(parts.join("metrics.json")).unwrap(), std::fs::read(out.join("metrics.json")).unwrap());
}

#[test]
fn a_sequence_starts_from_a_base_policy_and_keeps_its_task() {
    let tmp = tempfile::tempdir().unwrap();
    let smoke_cfg = quadcl::engine::RunConfig::load(&smoke()).unwrap();
    let mut base_cfg = smoke_cfg.config.clone();
    base_cfg.ppo.iterations = 2;
    let base = tmp.path().join("base");
    let mut env =
        quadcl::rl::SimTrainEnv::new(&base_cfg.env, &quadcl::sim::Perturbation::none(), base_cfg.ppo.num_envs, 1)
            .unwrap();
    quadcl::rl::train(&base_cfg, "none", &mut env, &base, false).unwrap();

    let text = std::fs::read_to_string(smoke())
        .unwrap()
        .replace("[method]", &format!("[run]\nbase_policy = {:?}\n\n[method]", base.join("policy")));
    let run_file = tmp.path().join("from-base.toml");
    std::fs::write(&run_file, text).unwrap();
    let m = run(&run_file, &tmp.path().join("out"), RunOptions { stop_after: Some(2), ..Default::default() }).unwrap();
    assert_eq!(m.tasks[0], "none");
    assert_eq!(m.tasks.len(), 4);
    assert_eq!(m.steps[0].task, 1, "the sequence's first task gets the next id");
    let base_evals: Vec<_> =
        m.evaluations.iter().map(|row| row.iter().find(|e| e.report.task == "none").unwrap().clone()).collect();
    assert_eq!(base_evals.len(), 2);
    assert_eq!(base_evals[0], base_evals[1], "the base task is recalled bit for bit");

    // Under other acting settings the recalled weights would act differently: refused, naming each.
    let text = std::fs::read_to_string(&run_file).unwrap().replace("episode_s = 2.0\n", "episode_s = 2.0\nkp = 31.0\n");
    let other = tmp.path().join("other-gains.toml");
    std::fs::write(&other, text).unwrap();
    let err = format!("{:#}", run(&other, &tmp.path().join("refused"), RunOptions::default()).unwrap_err());
    assert!(err.contains("env.kp") && err.contains("31") && err.contains("policy"), "{err}");
    assert!(!tmp.path().join("refused/metrics.json").exists(), "nothing was written");
}

#[test]
fn evaluating_a_learned_task_in_the_middle_of_a_step_changes_no_number_of_the_run() {
    use quadcl::engine::{ChannelObserver, Command, Event, OpenMode, Runner, StepOutcome};
    let tmp = tempfile::tempdir().unwrap();
    let mut plain = Runner::open(&smoke(), &tmp.path().join("plain"), OpenMode::New, false).unwrap();
    assert_eq!(plain.train(None).unwrap(), StepOutcome::SequenceDone);

    let mut probed = Runner::open(&smoke(), &tmp.path().join("probed"), OpenMode::New, false).unwrap();
    let (tx, events) = std::sync::mpsc::channel();
    probed.session_mut().add_observer(Box::new(ChannelObserver(tx)));
    probed.train(Some(1)).unwrap();
    probed.session_mut().step_iteration().unwrap();
    probed.session().command_sender().send(Command::Evaluate("crash:FL".into())).unwrap();
    assert_eq!(probed.train(None).unwrap(), StepOutcome::SequenceDone);
    let now = events.try_iter().find_map(|e| match e {
        Event::EvaluatedNow { evaluation } => Some(evaluation),
        _ => None,
    });
    let now = now.expect("evaluated in the middle of step 1");
    let (a, b) = (plain.metrics(), probed.metrics());
    assert_eq!(a.curves, b.curves);
    assert_eq!(a.eval_matrix, b.eval_matrix);
    assert_eq!(a.evaluations, b.evaluations);
    assert_eq!(&now, b.evaluations[1].iter().find(|e| e.report.task == "crash:FL").unwrap(), "the same recall");
}

#[test]
fn a_run_with_record_keeps_one_mcap_episode_of_every_learned_task_after_each_step() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("rec");
    run(&smoke(), &out, RunOptions { record: Some(RecordFormat::Mcap), ..Default::default() }).unwrap();
    for (step, expected) in [
        ("step-00-crash_FL", vec!["crash_FL.mcap"]),
        ("step-02-noise_FR", vec!["crash_FL.mcap", "invert_RR.mcap", "noise_FR.mcap"]),
    ] {
        let folder = out.join("episodes").join(step);
        let mut names: Vec<String> = std::fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, expected, "{step}");
        let bytes = std::fs::read(folder.join(expected[0])).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let stats = summary.stats.unwrap();
        assert!(stats.message_count > 6, "an episode's messages");
    }
    let toy = tmp.path().join("toy.toml");
    std::fs::write(&toy, "[run]\nlearner = \"toy\"\n[[task]]\nname = \"crash:FL\"\n").unwrap();
    let err = format!(
        "{:#}",
        run(&toy, &tmp.path().join("t"), RunOptions { record: Some(RecordFormat::Mcap), ..Default::default() })
            .unwrap_err()
    );
    assert!(err.contains("--record") && err.contains("toy"), "{err}");
}

#[test]
fn every_baseline_runs_the_smoke_sequence_on_dense_networks_and_its_checkpoints_evaluate() {
    let tmp = tempfile::tempdir().unwrap();
    for method in ["finetune", "ewc", "si", "rwalk"] {
        let out = tmp.path().join(method);
        let m = run(&smoke(), &out, RunOptions { method: Some(method.into()), ..Default::default() }).unwrap();
        assert_eq!((m.completed_steps, m.method.as_str()), (3, method));
        let json = assert_metrics_json_complete(&out);
        assert_eq!(json["method_settings"].is_object(), method != "finetune", "{method}");
        assert!(m.summary.average_performance.is_some_and(f64::is_finite), "{method}");
        let last = out.join("checkpoints/step-02-noise_FR");
        let report = quadcl::nn::MaskReport::of_policy(&last).unwrap();
        let trunk = &report.networks[0].layers[0];
        assert_eq!((trunk.vacant, trunk.per_task.len()), (0, 3), "{method}: the trunk is shared by every task");
        for name in &m.tasks {
            let loaded = quadcl::rl::load_policy(&last, Some(name)).unwrap();
            assert_eq!(loaded.agent.network_kind(), quadcl::nn::NetworkKind::Dense);
        }
    }
}

#[test]
fn every_mask_baseline_runs_the_smoke_sequence_and_forgets_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    for method in ["wsn", "packnet", "piggyback"] {
        let out = tmp.path().join(method);
        let m = run(&smoke(), &out, RunOptions { method: Some(method.into()), ..Default::default() }).unwrap();
        assert_eq!((m.completed_steps, m.method.as_str()), (3, method));
        assert_eq!(m.summary.forgetting, Some(0.0), "{method}");
        let json = assert_metrics_json_complete(&out);
        assert_eq!(
            json["steps"][0].get("switches").is_some(),
            method == "wsn",
            "{method}: switches only where they act"
        );
    }
}

/// Issue 36: the smoke sequence on the aliengo (`scenes/smoke-aliengo.toml`) trains on the robot
/// files of the fuzz corpus that ROS packages ship: one with `<transmission>`, `<gazebo>` and
/// `<ros2_control>` blocks, one whose `package://` and `file://` meshes resolve nowhere.
#[test]
fn the_smoke_sequence_trains_on_robot_files_with_ros_extensions_and_unresolved_meshes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let aliengo = std::fs::read_to_string(root.join("scenes/smoke-aliengo.toml")).unwrap();
    assert!(aliengo.contains("urdf = \"scenes/aliengo.urdf\""));
    let tmp = tempfile::tempdir().unwrap();
    for file in ["ros-extensions", "unresolved-meshes"] {
        let config = tmp.path().join(format!("{file}.toml"));
        let urdf = format!("urdf = \"tests/fuzz_corpus/{file}.urdf\"");
        std::fs::write(&config, aliengo.replace("urdf = \"scenes/aliengo.urdf\"", &urdf)).unwrap();
        let m = run(&config, &tmp.path().join(file), RunOptions::default()).unwrap();
        assert_eq!(m.completed_steps, 3, "{file}");
        assert_eq!(m.summary.forgetting, Some(0.0), "{file}");
    }
}

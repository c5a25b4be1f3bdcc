//! Nothing a user can type allocates without bound, and values that make a
//! run meaningless are refused: each error names the file or option, the key
//! and the limit (issue 16, items 1 and 2).

use std::path::Path;
use std::process::Command;

fn quadcl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_quadcl")).current_dir(env!("CARGO_MANIFEST_DIR")).args(args).output().unwrap()
}

#[test]
fn a_huge_episode_count_is_refused_at_once_with_the_limit() {
    for episodes in ["100000000", "16385", "0"] {
        let out = quadcl(&["eval", "--policy", "policies/base-a1-flat", "--task", "none", "--episodes", episodes]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("--episodes") && err.contains("16384"), "{episodes}: {err}");
    }
}

#[test]
fn run_files_with_sizes_that_cannot_fit_or_ranges_that_cannot_work_name_the_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let smoke = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml")).unwrap();
    for (from, to, key) in [
        ("episodes = 4", "episodes = 100000000", "[eval] episodes"),
        ("num_envs = 8", "num_envs = 0", "ppo.num_envs"),
        ("num_envs = 8", "num_envs = 1000000", "at most 16384"),
        ("hidden = [64, 32]", "hidden = [0, 32]", "net.actor.hidden"),
        ("episode_s = 2.0", "episode_s = 2.0\nmotor_strength_range = [-5.0, -5.0]", "env.motor_strength_range"),
        ("episode_s = 2.0", "episode_s = 2.0\nfriction_range = [-1.0, 1.0]", "env.friction_range"),
    ] {
        assert!(smoke.contains(from), "{from}");
        let path = dir.path().join("bad-run.toml");
        std::fs::write(&path, smoke.replacen(from, to, 1)).unwrap();
        let out =
            quadcl(&["run", "--config", path.to_str().unwrap(), "--out", dir.path().join("out").to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("bad-run.toml") && err.contains(key), "{to}: {err}");
        assert!(!dir.path().join("out").join("metrics.json").exists(), "{to}: nothing ran");
    }
}

#[test]
fn a_shift_file_latency_beyond_the_limit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shift.toml");
    for latency in ["1e12", "11.0", "-1.0", "nan"] {
        std::fs::write(&path, format!("latency_s = {latency}\n")).unwrap();
        let err = format!("{:#}", quadcl::engine::Shift::load(&path).unwrap_err());
        assert!(err.contains("shift.toml") && err.contains("latency_s") && err.contains("[0, 10]"), "{latency}: {err}");
    }
}

/// Writes `text` to `dir/name` and returns the error of loading it with `load`, with its context.
fn load_error<T>(dir: &Path, name: &str, text: &str, load: impl Fn(&Path) -> anyhow::Result<T>) -> Option<String> {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    load(&path).err().map(|e| format!("{e:#}"))
}

#[test]
fn every_shipped_config_and_run_file_still_loads() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> =
        std::fs::read_dir(root.join("scenes")).unwrap().map(|e| e.unwrap().path()).collect::<Vec<_>>();
    // One level of folders under scenes/ (scenes/tuning/).
    let folders: Vec<_> = files.iter().filter(|p| p.is_dir()).cloned().collect();
    for folder in folders {
        files.extend(std::fs::read_dir(folder).unwrap().map(|e| e.unwrap().path()));
    }
    for policy in std::fs::read_dir(root.join("policies")).unwrap() {
        let policy = policy.unwrap().path();
        for sub in std::iter::once(policy.clone())
            .chain(std::fs::read_dir(&policy).into_iter().flatten().flatten().map(|e| e.path()))
        {
            files.extend(["config.toml", "run.toml"].map(|f| sub.join(f)).into_iter().filter(|p| p.is_file()));
        }
    }
    // Shift files (`quadcl finetune --shift`) are not configs; fig11-transfer plans only after
    // its reference sweep ran (tests/findings_scenes.rs checks both cases).
    files.retain(|p| p.extension().is_some_and(|e| e == "toml"));
    files.retain(|p| !p.to_string_lossy().ends_with(".shift.toml") && !p.ends_with("findings/fig11-transfer.toml"));
    let (mut configs, mut runs) = (0, 0);
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        if text.lines().any(|l| l.trim() == "[axes]") {
            // A sweep file: every cell of it is a run file that loads.
            quadcl::sweep::plan::check(path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
        } else if text.lines().any(|l| l.trim() == "[[task]]") {
            quadcl::engine::RunConfig::load(path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
            runs += 1;
        } else {
            quadcl::config::Config::load(path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
            configs += 1;
        }
    }
    assert!(configs >= 5 && runs >= 20, "{configs} configs and {runs} run files");
}

#[test]
fn every_config_key_out_of_its_range_is_an_error_naming_the_file_and_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for (text, key) in [
        ("[env]\nphysics_dt = 0.0", "env.physics_dt"),
        ("[env]\nphysics_dt = 1.0", "env.physics_dt"),
        ("[env]\ndecimation = 0", "env.decimation"),
        ("[env]\nsolver_iterations = 100000", "env.solver_iterations"),
        ("[env]\nepisode_s = 0.001", "env.episode_s"),
        ("[env]\nepisode_s = inf", "env.episode_s"),
        ("[env]\nepisode_s = 1e9", "env.episode_s"),
        ("[env]\ncmd_vx = [-100.0, 1.0]", "env.cmd_vx"),
        ("[env]\ncmd_wz = [nan, 1.0]", "env.cmd_wz"),
        ("[env]\nmax_tilt_rad = 0.0", "env.max_tilt_rad"),
        ("[env]\nsoft_limit_fraction = 1.5", "env.soft_limit_fraction"),
        ("[env]\naction_scale = 0.0", "env.action_scale"),
        ("[env]\nclip_actions = nan", "env.clip_actions"),
        ("[env]\nheight_target = -0.3", "env.height_target"),
        ("[env]\ncommand_resample_s = inf", "env.command_resample_s"),
        ("[env.rewards]\ntorques = nan", "env.rewards.torques"),
        ("[env.rewards]\ncollision = -inf", "env.rewards.collision"),
        ("[env.robot.kd]\n\"*\" = -1.0", "env.robot.kd.\"*\""),
        ("[ppo]\niterations = 0", "ppo.iterations"),
        ("[ppo]\nepochs = 100000", "ppo.epochs"),
        ("[ppo]\nlog_every = 0", "ppo.log_every"),
        ("[ppo]\nclip_ratio = inf", "ppo.clip_ratio"),
        ("[ppo]\nmax_lr = inf", "ppo.max_lr"),
        ("[ppo]\nlearning_rate = 0.5\nmax_lr = 0.1", "max_lr"),
        ("[ppo]\nvalue_loss_coef = -1.0", "ppo.value_loss_coef"),
        ("[ppo]\nentropy_coef = nan", "ppo.entropy_coef"),
        ("[ppo]\nmax_grad_norm = 0.0", "ppo.max_grad_norm"),
        ("[ppo]\ndesired_kl = 0.0", "ppo.desired_kl"),
        ("[ppo]\nlr_factor = inf", "ppo.lr_factor"),
        ("[ppo]\ncenet_beta = nan", "ppo.cenet_beta"),
        ("[ppo]\ncenet_logvar_clamp = 0.0", "ppo.cenet_logvar_clamp"),
        ("[ppo]\ncenet_decoder_hidden = [60000, 60000]", "ppo.cenet_decoder_hidden"),
        ("[ppo]\nminibatches = 100000", "ppo.minibatches"),
        ("[net.mask]\ncapacity = 0.0", "net.mask.capacity"),
        ("[net.mask]\nsigma_init = 0.0", "net.mask.sigma_init"),
        ("[net.mask]\nsigma_init = inf", "net.mask.sigma_init"),
        ("[net.mask]\nsigma_decay = 0.0", "net.mask.sigma_decay"),
        ("[net.mask]\nsigma_floor = 0.0", "net.mask.sigma_floor"),
        ("[net.mask]\npacknet_keep = 0.0", "net.mask.packnet_keep"),
        ("[net.mask]\npiggyback_init = 0.001", "net.mask.piggyback_init"),
        ("[net.mask]\nentropy_iterations = 100000000", "net.mask.entropy_iterations"),
        ("[net.mask]\nentropy_fraction = 1.5", "net.mask.entropy_fraction"),
        ("[net.mask]\nentropy_fraction = 0.2\nentropy_iterations = 100", "both set the entropy phase"),
        ("[net.mask]\nscore_learning_rate = -0.001", "net.mask.score_learning_rate"),
        ("[net.mask]\nvacant_share = nan", "net.mask.vacant_share"),
    ] {
        let err = load_error(dir.path(), "bad.toml", &format!("{text}\n"), quadcl::config::Config::load)
            .unwrap_or_else(|| panic!("{text}: accepted"));
        assert!(err.contains("bad.toml") && err.contains(key), "{text}: {err}");
    }
}

#[test]
fn a_capacity_that_selects_nothing_in_a_layer_is_an_error_naming_the_layer_and_the_least_capacity() {
    let dir = tempfile::tempdir().unwrap();
    // 0.002 * 128 rounds to 0: the actor's output layer (fan-in 128) would select nothing.
    for (text, layer) in [
        ("[net.mask]\ncapacity = 0.002\n", "net.actor layer l3 (output)"),
        ("[net.critic]\nhidden = [2]\n", "net.critic layer l1 (output)"),
        ("[net.actor]\nhidden = [8, 2]\n[net.mask]\ncapacity = 0.02\nrule = \"per-layer\"\n", "net.actor layer l1"),
    ] {
        let err = load_error(dir.path(), "small.toml", text, quadcl::config::Config::load).expect(text);
        assert!(err.contains("small.toml") && err.contains("selects nothing") && err.contains(layer), "{text}: {err}");
        assert!(err.contains("it needs a capacity of at least"), "{err}");
    }
    // The same capacity with wider layers selects something and loads.
    quadcl::config::Config::from_toml_str("[net.mask]\ncapacity = 0.01\n").unwrap();
}

#[test]
fn a_run_whose_tasks_train_nothing_or_whose_settings_select_nothing_names_the_file_task_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let task = "[[task]]\nname = \"crash:FL\"\n";
    for (text, key) in [
        (format!("iterations = 0\n{task}[[task]]\nname = \"none\"\n"), "iterations (the run's default"),
        (format!("{task}iterations = 0\n"), "task 1 (crash:FL): iterations = 0"),
        (format!("{task}iterations = 100000000\n"), "at most 10000000"),
        (format!("iterations = 6000000\n{task}[[task]]\nname = \"none\"\n"), "12000000 iterations in all"),
        (format!("{task}[task.switches]\ncapacity = 0.0\n"), "task 1 (crash:FL): in [task.switches]"),
        (format!("{task}[task.switches]\ncapacity = 0.001\n"), "selects nothing"),
        (format!("[method]\ncapacity = 0.001\n{task}"), "selects nothing"),
        (format!("[method]\nname = \"piggyback\"\n[method.piggyback]\ninit = 0.0\n{task}"), "[method.piggyback] init"),
        (
            format!("[method]\nname = \"packnet\"\n[method.packnet]\nretrain_iterations = 300\n{task}"),
            "retrain_iterations = 300",
        ),
        (format!("[method.packnet]\nretrain_iterations = 100000000\n{task}"), "[method.packnet] retrain_iterations"),
        (format!("[method.er]\nbuffer_size = 100000000\n{task}"), "[method.er] buffer_size"),
        (format!("[method.agem]\nbatch_size = 0\n{task}"), "[method.agem] batch_size"),
        (format!("[method.rwalk]\nalpha = 0.0\n{task}"), "[method.rwalk] alpha"),
        (format!("[method.ewc]\nfisher_samples = 100000000\n{task}"), "[method.ewc] fisher_samples"),
        (format!("[method.si]\nc = nan\n{task}"), "[method.si] c"),
        (format!("[run]\nbase_vacant = \"redrawn\"\n{task}"), "base_vacant = \"redrawn\" needs a base policy"),
        (format!("[run]\nlearner = \"toy\"\nvideos = true\n{task}"), "videos = true needs the PPO learner"),
    ] {
        let err = load_error(dir.path(), "bad-run.toml", &text, quadcl::engine::RunConfig::load)
            .unwrap_or_else(|| panic!("{text}: accepted"));
        assert!(err.contains("bad-run.toml") && err.contains(key), "{text}: {err}");
    }
    // A task whose own budget replaces a default of 0 trains, and PackNet with room to retrain loads.
    quadcl::engine::RunConfig::from_toml_str(&format!("iterations = 0\n{task}iterations = 5\n")).unwrap();
    let packnet = format!("[method]\nname = \"packnet\"\n[method.packnet]\nretrain_iterations = 299\n{task}");
    quadcl::engine::RunConfig::from_toml_str(&packnet).unwrap();
}

#[test]
fn a_run_of_zero_iterations_is_refused_by_quadcl_run_before_anything_trains() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty-run.toml");
    let smoke = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml")).unwrap();
    let text: String = smoke.lines().filter(|l| !l.starts_with("iterations")).map(|l| format!("{l}\n")).collect();
    std::fs::write(&path, format!("iterations = 0\n{text}")).unwrap();
    let out = quadcl(&["run", "--config", path.to_str().unwrap(), "--out", dir.path().join("out").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("empty-run.toml") && err.contains("iterations"), "{err}");
    assert!(!dir.path().join("out").join("metrics.json").exists());
}

#[test]
fn shift_file_ranges_and_budgets_name_the_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    for (text, key) in [
        ("iterations = 0", "iterations"),
        ("iterations = 100000000", "at most 10000000"),
        ("friction = [-1.0, 1.0]", "friction"),
        ("friction = [0.5, 0.2]", "low <= high"),
        ("motor_strength = [0.0, 1.0]", "motor_strength"),
        ("added_mass = [nan, 1.0]", "added_mass"),
    ] {
        let err = load_error(dir.path(), "shift.toml", &format!("{text}\n"), quadcl::engine::Shift::load)
            .unwrap_or_else(|| panic!("{text}: accepted"));
        assert!(err.contains("shift.toml") && err.contains(key), "{text}: {err}");
    }
}

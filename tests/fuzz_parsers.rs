//! Fuzzing every parser and loader (issue 16 item 7): no input panics. A
//! seeded mutation fuzzer on stable Rust (no nightly, no new dependency):
//! each target starts from a committed seed corpus (the shipped scenes,
//! `tests/fuzz_corpus/` and the shipped base policy; the figures' run files from
//! `tests/plot_fixture/`; the training-checkpoint
//! targets from a tiny training the test runs first), mutates it (byte flips, insertions of tokens the
//! format cares about, deletions, duplications, truncations) and feeds every
//! result to the loader, which may return an error but must not panic.
//!
//! `cargo test` runs each target for QUADCL_FUZZ_SECONDS (default 1 s);
//! `.ci/run` runs it for 60 s per target. A panic saves the input under
//! `target/fuzz-failures/` and names the file and the iteration's seed.

use quadcl::sim::RobotModel;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn seconds() -> f64 {
    std::env::var("QUADCL_FUZZ_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(1.0)
}

/// The corpus: shipped files matching `ext` under `scenes/` and `tests/fuzz_corpus/`.
fn corpus(ext: &str) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for dir in ["scenes", "tests/fuzz_corpus"] {
        let mut paths: Vec<PathBuf> =
            std::fs::read_dir(root().join(dir)).map(|d| d.flatten().map(|e| e.path()).collect()).unwrap_or_default();
        paths.sort();
        for p in paths.into_iter().filter(|p| p.to_string_lossy().ends_with(ext)) {
            out.push(std::fs::read(&p).unwrap());
        }
    }
    assert!(!out.is_empty(), "no seed files ending in {ext}");
    out
}

/// One mutation of `input` (several edits), drawn from `rng`.
fn mutate(input: &[u8], tokens: &[&str], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..rng.gen_range(1..=4) {
        let at = if v.is_empty() { 0 } else { rng.gen_range(0..=v.len()) };
        match rng.gen_range(0..6) {
            0 if !v.is_empty() => {
                let i = at.min(v.len() - 1);
                v[i] ^= 1 << rng.gen_range(0..8);
            }
            1 => {
                let t = tokens[rng.gen_range(0..tokens.len())].as_bytes();
                v.splice(at..at, t.iter().copied());
            }
            2 if !v.is_empty() => {
                let end = (at + rng.gen_range(1..64)).min(v.len());
                v.drain(at.min(end)..end);
            }
            3 if !v.is_empty() => {
                let start = rng.gen_range(0..v.len());
                let end = (start + rng.gen_range(1..256)).min(v.len());
                let piece = v[start..end].to_vec();
                v.splice(at..at, piece);
            }
            4 => v.truncate(at),
            _ => v.insert(at, rng.gen()),
        }
    }
    v
}

/// Runs `target` on mutations of `seeds` for the configured time; returns the iterations run.
fn fuzz(name: &str, seeds: &[Vec<u8>], tokens: &[&str], mut target: impl FnMut(&[u8])) -> usize {
    let deadline = Instant::now() + Duration::from_secs_f64(seconds());
    let mut iteration = 0u64;
    let mut failure = None;
    while Instant::now() < deadline && failure.is_none() {
        let mut rng = ChaCha8Rng::seed_from_u64(iteration);
        let seed = &seeds[rng.gen_range(0..seeds.len())];
        let input = if iteration < seeds.len() as u64 {
            seeds[iteration as usize].clone()
        } else {
            mutate(seed, tokens, &mut rng)
        };
        if std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| target(&input))).is_err() {
            failure = Some((iteration, input));
        }
        iteration += 1;
    }
    if let Some((iteration, input)) = failure {
        let dir = root().join("target/fuzz-failures");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{name}-{iteration}"));
        std::fs::write(&path, &input).unwrap();
        panic!("{name}: input {} (iteration seed {iteration}) panicked", path.display());
    }
    eprintln!("fuzz {name}: {iteration} inputs in {:.0} s, no panic", seconds());
    iteration as usize
}

const URDF_TOKENS: &[&str] = &[
    "<",
    ">",
    "/>",
    "=\"",
    "\"",
    " ",
    "nan",
    "inf",
    "-1e308",
    "1e39",
    "0",
    "-",
    "<link name=\"x\"/>",
    "</link>",
    "<joint name=\"j\" type=\"fixed\"><parent link=\"trunk\"/><child link=\"x\"/></joint>",
    "type=\"continuous\"",
    "type=\"prismatic\"",
    "<mesh filename=\"package://p/m.stl\"/>",
    "<sphere radius=\"0\"/>",
    "<mass value=\"-1\"/>",
    "<limit effort=\"1\" velocity=\"1\"/>",
    "<material name=\"m\"/>",
    "<!--",
    "-->",
    "&amp;",
    "<![CDATA[",
    "]]>",
];

const TOML_TOKENS: &[&str] = &[
    "=",
    "[",
    "]",
    "[[task]]\nname = \"none\"\n",
    "\"",
    "\n",
    "0",
    "-1",
    "nan",
    "inf",
    "1e300",
    "18446744073709551615",
    "[env]\n",
    "[ppo]\nnum_envs = ",
    "[net.actor]\nhidden = [",
    "[env.robot.default_pose]\n\"*\" = ",
    "[method]\n",
    "name = \"crash:FL+invert:FL\"\n",
    "related = [\"none\"]\n",
    "iterations = 0\n",
    "latency_s = ",
    "true",
    "{",
    "}",
];

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn fuzz_urdf_loader() {
    let seeds = corpus(".urdf");
    let n = fuzz("urdf", &seeds, URDF_TOKENS, |input| {
        if let Ok(robot) = RobotModel::from_urdf_str(&text(input), Path::new("/nonexistent/robot.urdf")) {
            // A description that loads must also build a world (or fail cleanly).
            let cfg = quadcl::config::EnvConfig::default();
            let _ = quadcl::sim::LocomotionEnv::new(&cfg, &robot, &quadcl::sim::Perturbation::none());
        }
    });
    assert!(n > 0);
}

#[test]
fn fuzz_config_and_run_files() {
    let seeds = corpus(".toml");
    fuzz("toml", &seeds, TOML_TOKENS, |input| {
        let s = text(input);
        let _ = quadcl::config::Config::from_toml_str(&s);
        let _ = quadcl::engine::RunConfig::from_toml_str(&s);
    });
}

#[test]
fn fuzz_shift_files() {
    let seeds = corpus(".shift.toml");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shift.toml");
    fuzz("shift", &seeds, TOML_TOKENS, |input| {
        std::fs::write(&path, input).unwrap();
        let _ = quadcl::engine::Shift::load(&path);
    });
}

#[test]
fn fuzz_task_names() {
    let seeds: Vec<Vec<u8>> = ["none", "crash:FL", "invert:RR+noise:FR", "noise:RL+crash:FR+invert:FL"]
        .iter()
        .map(|s| s.as_bytes().to_vec())
        .collect();
    let tokens = &["+", ":", "FL", "RR", "crash", "invert", "noise", "none", " ", "", "\u{0}", "é"];
    fuzz("task", &seeds, tokens, |input| {
        if let Ok(p) = text(input).parse::<quadcl::sim::Perturbation>() {
            // What parses prints back to a name that parses to the same thing.
            assert_eq!(p.to_string().parse::<quadcl::sim::Perturbation>().unwrap(), p);
        }
    });
}

#[test]
fn fuzz_policy_directories() {
    let shipped = root().join("policies/base-a1-flat");
    let dir = tempfile::tempdir().unwrap();
    for f in ["manifest.json", "model.safetensors", "masks.safetensors"] {
        std::fs::copy(shipped.join(f), dir.path().join(f)).unwrap();
    }
    let manifest = std::fs::read(shipped.join("manifest.json")).unwrap();
    let masks = std::fs::read(shipped.join("masks.safetensors")).unwrap();
    let tokens = &["{", "}", "[", "]", "\"", ",", ":", "0", "-1", "1e308", "null", "\"tasks\": []", "999999999999"];
    // The manifest's text, and the masks file's bytes (its hash is checked first, so a
    // mutated tensor file mostly tests that check; the header parser sees some of it too).
    fuzz("policy-manifest", std::slice::from_ref(&manifest), tokens, |input| {
        std::fs::write(dir.path().join("manifest.json"), input).unwrap();
        let _ = quadcl::nn::checkpoint::load_policy(dir.path());
        let _ = quadcl::rl::load_policy_or_checkpoint(dir.path());
    });
    std::fs::write(dir.path().join("manifest.json"), &manifest).unwrap();
    fuzz("policy-masks", std::slice::from_ref(&masks), &["\u{0}", "{\"", "\"}", "F32"], |input| {
        std::fs::write(dir.path().join("masks.safetensors"), input).unwrap();
        let _ = quadcl::nn::checkpoint::load_policy(dir.path());
    });
}

#[test]
fn fuzz_training_checkpoints() {
    // A real training state (tiny networks, 3 robots, 2 iterations: checkpoints at both),
    // then its bytes mutated: reading must not panic, and what reads is restored into the
    // learner and envs of that checkpoint, which may refuse it but must not panic either.
    use quadcl::config::{Config, PpoConfig};
    use quadcl::rl::{load_resume_point, train_from, PpoLearner, SimTrainEnv, TrainingState, TRAINING_STATE_FILE};
    let mut cfg = Config {
        ppo: PpoConfig {
            num_envs: 3,
            steps_per_env: 8,
            iterations: 2,
            checkpoint_every: 1,
            cenet_decoder_hidden: vec![4],
            cenet_latent_dim: 2,
            ..PpoConfig::default()
        },
        ..Config::default()
    };
    cfg.env.episode_s = 0.1;
    cfg.net.actor.hidden = vec![4];
    cfg.net.critic.hidden = vec![4];
    cfg.net.cenet.hidden = vec![4];
    let none = quadcl::sim::Perturbation::none();
    let run = tempfile::tempdir().unwrap();
    let mut env = SimTrainEnv::new(&cfg.env, &none, 3, cfg.seed).unwrap();
    train_from(&cfg, "none", &mut env, run.path(), false, true, None).unwrap();
    let state = std::fs::read(run.path().join("checkpoint").join(TRAINING_STATE_FILE)).unwrap();
    let point = load_resume_point(&cfg, "none", run.path()).unwrap();
    let mut learner = PpoLearner::new(cfg.ppo.clone(), point.agent, 3, 0).unwrap();
    let mut env = SimTrainEnv::new(&cfg.env, &none, 3, cfg.seed).unwrap();
    let path = run.path().join("fuzzed.safetensors");
    let tokens = &["\u{0}", "\u{ff}", "{\"", "\"}", "F32", "U64", "U8", "F64", "[0]", "[99999999]", "adam.", ".step"];
    fuzz("training-state", std::slice::from_ref(&state), tokens, |input| {
        std::fs::write(&path, input).unwrap();
        if let Ok(read) = TrainingState::read(&path) {
            let _ = read.restore(&mut learner, &mut env);
        }
    });

    // The checkpoint's model file, mutated, with the manifest's hash of it made to match, so
    // the tensor reader and every check behind the hash see the mutations.
    let checkpoint = run.path().join("checkpoint");
    let copy = run.path().join("mutated");
    std::fs::create_dir_all(&copy).unwrap();
    for f in ["masks.safetensors", "manifest.json"] {
        std::fs::copy(checkpoint.join(f), copy.join(f)).unwrap();
    }
    let model = std::fs::read(checkpoint.join("model.safetensors")).unwrap();
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(checkpoint.join("manifest.json")).unwrap()).unwrap();
    fuzz("checkpoint-model", std::slice::from_ref(&model), tokens, |input| {
        let mut m = manifest.clone();
        m["files"]["model.safetensors"] = quadcl::util::sha256_hex(input).into();
        std::fs::write(copy.join("manifest.json"), serde_json::to_vec(&m).unwrap()).unwrap();
        std::fs::write(copy.join("model.safetensors"), input).unwrap();
        let _ = quadcl::rl::load_policy_or_checkpoint(&copy);
    });
}

#[test]
fn fuzz_sweep_files() {
    let seeds = corpus(".toml");
    let base: toml::Value =
        toml::from_str(&std::fs::read_to_string(root().join("scenes/smoke.toml")).unwrap()).unwrap();
    let tokens: Vec<&str> =
        TOML_TOKENS.iter().copied().chain(["base = \"smoke.toml\"\n", "[axes]\n", "\"task.0.", "."]).collect();
    fuzz("sweep-file", &seeds, &tokens, |input| {
        if let Ok(sweep) = quadcl::sweep::SweepFile::parse(Path::new("/nonexistent/sweep.toml"), &text(input)) {
            for axis in &sweep.axes {
                for value in &axis.values {
                    let mut run = base.clone();
                    let _ = quadcl::sweep::file::set_dotted(&mut run, &axis.key, value.clone());
                }
            }
        }
    });
}

#[test]
fn fuzz_sweep_plans() {
    // The fixture's sweep.json, mutated, read back by status and collect over its run folders.
    let fixture = root().join("tests/sweep_fixture");
    let dir = tempfile::tempdir().unwrap();
    for i in 0..6 {
        let run = dir.path().join(format!("runs/{i}"));
        std::fs::create_dir_all(&run).unwrap();
        std::fs::copy(fixture.join(format!("runs/{i}/metrics.json")), run.join("metrics.json")).unwrap();
    }
    let plan = std::fs::read(fixture.join("sweep.json")).unwrap();
    let tokens =
        &["{", "}", "[", "]", "\"", ",", ":", "0", "-1", "1e308", "null", "18446744073709551615", "\"runs/0\""];
    fuzz("sweep-plan", std::slice::from_ref(&plan), tokens, |input| {
        std::fs::write(dir.path().join("sweep.json"), input).unwrap();
        let _ = quadcl::sweep::status(dir.path(), false);
        let _ = quadcl::sweep::collect(dir.path());
    });
}

#[test]
fn fuzz_run_metrics_for_figures() {
    use quadcl::plot::{load_run, render_svg, Figure, PlotOptions};
    let seeds = vec![std::fs::read(root().join("tests/plot_fixture/two-tasks/metrics.json")).unwrap()];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("metrics.json");
    let tokens = &[
        "{",
        "}",
        "[",
        "]",
        ",",
        "null",
        "\"",
        "-1",
        "0",
        "1e308",
        "-1e308",
        "18446744073709551615",
        "\"plasticity/dormant/x\": [1, 2]",
        "\"rows\": [[]]",
        "\"trained\": [99]",
    ];
    fuzz("plot-metrics", &seeds, tokens, |input| {
        std::fs::write(&path, input).unwrap();
        // A file that loads must draw every figure (or fail cleanly).
        if let Ok(run) = load_run(&path, None) {
            let runs = [run];
            for figure in Figure::ALL.into_iter().filter(|f| f.applies_to(&runs)) {
                let _ = render_svg(figure, &runs, &PlotOptions::default());
            }
        }
    });
}

//! `quadcl export` on the shipped policies: every learned task of a masked
//! policy and of a dense method's policy becomes plain dense networks whose
//! actions equal the policy's own recall; the ONNX file is a well-formed graph
//! (read back with a small protobuf reader); the safetensors file has PyTorch's
//! nn.Sequential keys; the contract is in both. The parity in a real runtime
//! (ONNX Runtime) is `scripts/check_export.py`, run by `.ci/run`.

use quadcl::export::{self, dense_policy::DensePolicy, ExportFormat, SELF_CHECK_TOLERANCE};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The shipped adapter run's last checkpoint: a masked policy with four learned tasks and the base.
fn masked_policy() -> PathBuf {
    root().join("policies/sequence-a1-adapter/checkpoints/step-03-crash_FR")
}

/// EWC's last checkpoint from the comparison: a dense trunk with one head per task.
fn dense_policy() -> PathBuf {
    root().join("policies/compare-a1/ewc/checkpoints/step-03-crash_FR")
}

fn dense_copy(dir: &Path, task: &str) -> DensePolicy {
    let loaded = export::load_task(dir, Some(task)).unwrap();
    let robot = export::contract::RobotFacts::of(&loaded.info.config.env).unwrap();
    DensePolicy::from_loaded(&loaded, &robot.default_pose, &robot.limits).unwrap()
}

#[test]
fn every_task_of_a_masked_policy_exports_with_the_actions_of_its_recall() {
    let out = tempfile::tempdir().unwrap();
    let tasks = export::learned_tasks(&masked_policy()).unwrap();
    assert!(tasks.len() >= 4, "{tasks:?}");
    for task in &tasks {
        let file = out.path().join(format!("{}.onnx", export::task_file_stem(task)));
        let done = export::export_task(&masked_policy(), Some(task), ExportFormat::Onnx, &file, None).unwrap();
        assert_eq!(&done.task, task);
        assert!(done.self_check <= SELF_CHECK_TOLERANCE, "{task}: {}", done.self_check);
        assert_eq!(std::fs::metadata(&file).unwrap().len() as usize, done.bytes);
    }
}

#[test]
fn a_dense_method_exports_its_trunk_with_the_task_head() {
    let out = tempfile::tempdir().unwrap();
    for task in ["crash:FL", "crash:FR"] {
        let file = out.path().join("ewc.safetensors");
        let done = export::export_task(&dense_policy(), Some(task), ExportFormat::Safetensors, &file, None).unwrap();
        assert!(done.self_check <= SELF_CHECK_TOLERANCE, "{task}: {}", done.self_check);
    }
}

#[test]
fn two_tasks_of_one_policy_export_different_networks() {
    // The same observations give different actions under crash:FL's masks and invert:RL's:
    // the export applies the task's parameters, not a shared or last one.
    let a = dense_copy(&masked_policy(), "crash:FL");
    let b = dense_copy(&masked_policy(), "invert:RL");
    let history = vec![0.1f32; a.history_width() * 2];
    let (ya, yb) = (a.forward(&history).unwrap(), b.forward(&history).unwrap());
    let diff = ya.actions.iter().zip(&yb.actions).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    assert!(diff > 1e-2, "crash:FL and invert:RL act alike: max |diff| {diff}");
}

#[test]
fn a_task_the_policy_has_not_learned_is_an_error_naming_the_learned_ones() {
    let out = tempfile::tempdir().unwrap();
    let file = out.path().join("x.onnx");
    let err = export::export_task(&dense_policy(), Some("invert:FL"), ExportFormat::Onnx, &file, None).unwrap_err();
    let text = format!("{err:#}");
    assert!(text.contains("invert:FL") && text.contains("crash:FL"), "{text}");
    assert!(!file.exists(), "nothing is written for a bad task");
}

/// A protobuf message read back: field number -> raw values (varints as u64, length-delimited as bytes).
#[derive(Debug, Default)]
struct Fields {
    ints: BTreeMap<u32, Vec<u64>>,
    bytes: BTreeMap<u32, Vec<Vec<u8>>>,
}

fn varint(data: &[u8], at: &mut usize) -> u64 {
    let mut value = 0u64;
    for shift in (0..64).step_by(7) {
        let b = data[*at];
        *at += 1;
        value |= u64::from(b & 0x7f) << shift;
        if b < 0x80 {
            break;
        }
    }
    value
}

fn read(data: &[u8]) -> Fields {
    let mut f = Fields::default();
    let mut at = 0;
    while at < data.len() {
        let key = varint(data, &mut at);
        let (field, wire) = ((key >> 3) as u32, key & 7);
        match wire {
            0 => f.ints.entry(field).or_default().push(varint(data, &mut at)),
            2 => {
                let len = varint(data, &mut at) as usize;
                f.bytes.entry(field).or_default().push(data[at..at + len].to_vec());
                at += len;
            }
            5 => at += 4,
            other => panic!("wire type {other} is not written by the exporter"),
        }
    }
    f
}

fn strings(f: &Fields, field: u32) -> Vec<String> {
    f.bytes.get(&field).into_iter().flatten().map(|b| String::from_utf8(b.clone()).unwrap()).collect()
}

#[test]
fn the_onnx_model_is_a_well_formed_graph_carrying_the_contract() {
    let out = tempfile::tempdir().unwrap();
    let file = out.path().join("crash_FL.onnx");
    export::export_task(&masked_policy(), Some("crash:FL"), ExportFormat::Onnx, &file, None).unwrap();
    let model = read(&std::fs::read(&file).unwrap());
    assert_eq!(model.ints[&1], [8], "IR version 8");
    let opset = read(&model.bytes[&8][0]);
    assert_eq!(opset.ints[&2], [17], "opset 17");
    let metadata: BTreeMap<String, String> = model.bytes[&14]
        .iter()
        .map(|entry| {
            let e = read(entry);
            (strings(&e, 1)[0].clone(), strings(&e, 2)[0].clone())
        })
        .collect();
    for key in ["task", "joint_names", "default_joint_pos", "kp", "kd", "action_scale", "control_dt", "obs_layout"] {
        assert!(metadata.contains_key(key), "metadata lacks {key}: {:?}", metadata.keys());
    }
    assert_eq!(metadata["task"], "\"crash:FL\"");
    let joints: Vec<String> = serde_json::from_str(&metadata["joint_names"]).unwrap();
    assert_eq!(joints.len(), 12);
    assert!(joints[0].starts_with("FL_"), "action order starts with the front-left hip: {joints:?}");

    let graph = read(&model.bytes[&7][0]);
    // Every value a node reads is the graph's input, an initializer, or an earlier node's output.
    let mut defined: HashSet<String> = graph.bytes[&11].iter().flat_map(|v| strings(&read(v), 1)).collect();
    for init in &graph.bytes[&5] {
        let t = read(init);
        let elements: u64 = t.ints.get(&1).map_or(1, |d| d.iter().product());
        let packed_dims = t.bytes.get(&1).map(|d| {
            let mut at = 0;
            let mut n = 1u64;
            while at < d[0].len() {
                n *= varint(&d[0], &mut at);
            }
            n
        });
        let width = if t.ints[&2] == [1] { 4 } else { 8 };
        assert_eq!(t.bytes[&9][0].len() as u64, packed_dims.unwrap_or(elements) * width, "{:?}", strings(&t, 8));
        defined.extend(strings(&t, 8));
    }
    let mut ops = Vec::new();
    for node in &graph.bytes[&1] {
        let n = read(node);
        for input in strings(&n, 1) {
            assert!(defined.contains(&input), "node {:?} reads {input}, defined nowhere before it", strings(&n, 3));
        }
        defined.extend(strings(&n, 2));
        ops.push(strings(&n, 4)[0].clone());
    }
    let outputs: Vec<String> = graph.bytes[&12].iter().flat_map(|v| strings(&read(v), 1)).collect();
    assert_eq!(outputs, ["actions", "joint_targets"]);
    assert!(outputs.iter().all(|o| defined.contains(o)));
    // The normaliser, the encoder and the actor (3 + 4 Gemm layers with ELU between), the action transform.
    assert_eq!(ops.iter().filter(|o| *o == "Gemm").count(), 7, "{ops:?}");
    assert_eq!(ops.iter().filter(|o| *o == "Elu").count(), 5, "{ops:?}");
    assert_eq!(&ops[..3], ["Sub", "Mul", "Clip"]);
    assert_eq!(&ops[ops.len() - 4..], ["Mul", "Add", "Max", "Min"]);
}

#[test]
fn the_safetensors_export_has_pytorch_sequential_keys_and_the_task_weights() {
    let out = tempfile::tempdir().unwrap();
    let file = out.path().join("crash_FR.safetensors");
    let reference = out.path().join("crash_FR.safetensors.reference.safetensors");
    export::export_task(&dense_policy(), Some("crash:FR"), ExportFormat::Safetensors, &file, Some(&reference)).unwrap();
    let bytes = std::fs::read(&file).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let copy = dense_copy(&dense_policy(), "crash:FR");
    for (i, layer) in copy.actor.layers.iter().enumerate() {
        let w = st.tensor(&format!("actor.{}.weight", 2 * i)).unwrap();
        assert_eq!(w.shape(), [layer.outputs, layer.inputs], "nn.Linear's weight is (out, in)");
        let values: Vec<f32> = w.data().chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        assert_eq!(values, layer.weight);
        assert_eq!(st.tensor(&format!("actor.{}.bias", 2 * i)).unwrap().shape(), [layer.outputs]);
    }
    assert!(st.tensor("encoder.0.weight").is_ok() && st.tensor("obs_normalizer.mean").is_ok());
    let (_, header) = safetensors::SafeTensors::read_metadata(&bytes).unwrap();
    let meta = header.metadata().clone().unwrap();
    assert_eq!(meta["format"], "pt");
    let sizes: Vec<usize> = serde_json::from_str(&meta["actor_sizes"]).unwrap();
    assert_eq!(sizes.len(), copy.actor.layers.len() + 1);
    // The reference samples: quadcl's own actions on a rollout's histories, which the copy reproduces.
    let samples = std::fs::read(&reference).unwrap();
    let r = safetensors::SafeTensors::deserialize(&samples).unwrap();
    let rows = r.tensor("obs_history").unwrap().shape()[0];
    assert_eq!(rows, export::reference::SAMPLE_ENVS * export::reference::SAMPLE_STEPS);
    assert_eq!(r.tensor("actions").unwrap().shape(), [rows, 12]);
}

fn eval_with_command(command: &str) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["eval", "--policy"])
        .arg(masked_policy())
        .args(["--task", "crash:FL", "--episodes", "2", "--json", "--policy-cmd", command])
        .output()
        .unwrap()
}

/// A policy program in Python's standard library: every action 0 (the standing pose).
const STAND_STILL: &str = "python3 -c \"import os, sys\n\
e = lambda k: int(os.environ['QUADCL_' + k])\n\
step = e('NUM_ENVS') * e('HISTORY_LEN') * e('OBS_DIM') * 4\n\
while len(sys.stdin.buffer.read(step)) == step:\n    \
sys.stdout.buffer.write(bytes(e('NUM_ENVS') * e('ACT_DIM') * 4)); sys.stdout.buffer.flush()\"";

#[test]
fn eval_takes_its_actions_from_a_policy_command() {
    let out = eval_with_command(STAND_STILL);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["episodes"], 2);
    // Standing in the default pose under commands to walk: no progress, so the tracking
    // error is about the commanded speed, far from the learned policy's ~0.1 m/s.
    let err = report["lin_vel_err"].as_f64().unwrap();
    assert!(err > 0.2, "a robot that never moves tracked its commands to {err} m/s");
}

#[test]
fn a_policy_command_that_stops_answering_is_an_error_naming_it() {
    let out = eval_with_command("exit 3");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("policy command `exit 3`") && stderr.contains('3'), "{stderr}");
}

#[test]
fn the_contract_carries_the_world_the_policy_was_trained_in() {
    use quadcl::export::contract::{contract, RobotFacts};
    let loaded = quadcl::rl::load_policy_or_checkpoint(&masked_policy()).unwrap().policy;
    let env = &loaded.info.config.env;
    let robot = RobotFacts::of(env).unwrap();
    let policy = DensePolicy::from_loaded(&loaded, &robot.default_pose, &robot.limits).unwrap();
    let meta: BTreeMap<String, serde_json::Value> = contract(&policy, &robot, env, "masked", "test")
        .into_iter()
        .map(|(k, v)| (k, serde_json::from_str(&v).unwrap()))
        .collect();
    assert_eq!(meta["contract_version"], 2);
    // The URDF itself, and its hash, so another simulator builds the same robot.
    let text = meta["robot_urdf_text"].as_str().unwrap();
    assert!(text.contains("<robot") && meta["robot_urdf_sha256"] == quadcl::util::sha256_hex(text.as_bytes()));
    // The A1's efforts: 20 N m at the hips, 55 at thighs and calves (not 33.5 everywhere).
    let effort: Vec<f32> = serde_json::from_value(meta["joint_effort_limits"].clone()).unwrap();
    let names: Vec<String> = serde_json::from_value(meta["joint_names"].clone()).unwrap();
    for (name, e) in names.iter().zip(&effort) {
        let want = if name.contains("hip") { 20.0 } else { 55.0 };
        assert!((e - want).abs() < 1.0, "{name}: {e}");
    }
    assert_eq!(meta["start_height"], serde_json::json!(env.start_height));
    let damping: Vec<f32> = serde_json::from_value(meta["pd_law"]["effective_damping"].clone()).unwrap();
    assert!((damping[0] - (env.kd + env.kp * env.physics_dt)).abs() < 1e-5, "{damping:?}");
    assert_eq!(meta["termination"]["max_tilt_rad"], serde_json::json!(env.max_tilt_rad));
    assert_eq!(meta["commands"]["vx"], serde_json::json!(env.cmd_vx));
    assert_eq!(meta["training_world"]["friction_range"], serde_json::json!(env.friction_range));
}

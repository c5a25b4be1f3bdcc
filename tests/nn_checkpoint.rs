//! Policy directories: a save/load round trip recalls every task
//! bit-identically and can go on training; corrupt or mismatched files are
//! errors that name the file and the problem.

mod nn_common;
use candle_core::{Device, Tensor};
use nn_common::*;
use quadcl::nn::checkpoint::{load_policy, save_policy, MANIFEST_FILE, MASKS_FILE, MODEL_FILE};
use quadcl::nn::MaskConfig;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::path::Path;

fn trained_policy(dir: &Path) -> quadcl::nn::MaskedMlp {
    let ts = tasks(3, 11);
    let mut net = small_mlp(&MaskConfig::default(), 11);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for (id, t) in ts.iter().take(2).enumerate() {
        train_task(&mut net, id, t, 30, 1e-2, &mut rng);
    }
    // Leave task 2 in progress.
    net.begin_task(2, &[0]).unwrap();
    let extras = BTreeMap::from([("action_std.0".to_string(), Tensor::from_vec(vec![0.5f32; OUT], OUT, &Device::Cpu).unwrap())]);
    let names = vec!["none".to_string(), "crash:FL".to_string(), "invert:RR".to_string()];
    save_policy(dir, &names, &[&net], &extras, &serde_json::json!({"seed": 11})).unwrap();
    net
}

#[test]
fn round_trip_recalls_every_task_bit_identically_and_resumes_training() {
    let dir = tempfile::tempdir().unwrap();
    let net = trained_policy(dir.path());
    let policy = load_policy(dir.path()).unwrap();
    assert_eq!(policy.tasks, ["none", "crash:FL", "invert:RR"]);
    assert_eq!(policy.config["seed"], 11);
    assert_eq!(policy.extras["action_std.0"].to_vec1::<f32>().unwrap(), vec![0.5; OUT]);
    let loaded = policy.network("net").unwrap();
    for t in 0..2 {
        assert_eq!(bits(&loaded.forward_task(t, &probe()).unwrap()), bits(&net.forward_task(t, &probe()).unwrap()));
    }
    for (a, b) in loaded.layers().iter().zip(net.layers()) {
        assert_eq!(a.states(), b.states());
        assert_eq!(a.task_mask(1), b.task_mask(1));
    }
    assert_eq!(loaded.current_task(), Some(2));
    let mut loaded = load_policy(dir.path()).unwrap().networks.remove(0);
    loaded.begin_iteration(0, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
    assert_eq!(loaded.forward(&probe()).unwrap().dims(), &[32, OUT]);
}

fn load_error(dir: &Path) -> String {
    format!("{:#}", load_policy(dir).unwrap_err())
}

#[test]
fn corrupt_tensor_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    trained_policy(dir.path());
    let path = dir.path().join(MODEL_FILE);
    let mut bytes = std::fs::read(&path).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x55;
    std::fs::write(&path, bytes).unwrap();
    let err = load_error(dir.path());
    assert!(err.contains(MODEL_FILE) && err.contains("hash mismatch"), "{err}");
}

#[test]
fn masks_from_another_policy_are_rejected() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    trained_policy(a.path());
    let mut net = small_mlp(&MaskConfig::default(), 5);
    train_task(&mut net, 0, &tasks(1, 5)[0], 10, 1e-2, &mut ChaCha8Rng::seed_from_u64(5));
    save_policy(b.path(), &["none".into()], &[&net], &BTreeMap::new(), &serde_json::Value::Null).unwrap();
    std::fs::copy(b.path().join(MASKS_FILE), a.path().join(MASKS_FILE)).unwrap();
    let err = load_error(a.path());
    assert!(err.contains(MASKS_FILE), "{err}");
}

#[test]
fn wrong_format_version_or_broken_manifest_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    trained_policy(dir.path());
    let path = dir.path().join(MANIFEST_FILE);
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replace("\"format_version\": 1", "\"format_version\": 99")).unwrap();
    let err = load_error(dir.path());
    assert!(err.contains(MANIFEST_FILE) && err.contains("format version 99"), "{err}");
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    let err = load_error(dir.path());
    assert!(err.contains(MANIFEST_FILE) && err.contains("not a valid manifest"), "{err}");
    std::fs::remove_file(&path).unwrap();
    assert!(load_error(dir.path()).contains(MANIFEST_FILE));
}

#[test]
fn tensor_with_wrong_shape_is_an_error_naming_tensor_and_shapes() {
    // A consistent directory (hashes match) whose manifest claims another layer width.
    let dir = tempfile::tempdir().unwrap();
    trained_policy(dir.path());
    let path = dir.path().join(MANIFEST_FILE);
    let mut m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    m["networks"][0]["sizes"][1] = 63.into();
    m["networks"][0]["layers"][0]["shape"][0] = 63.into();
    m["networks"][0]["layers"][1]["shape"][1] = 63.into();
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    let err = load_error(dir.path());
    assert!(err.contains(MODEL_FILE) && err.contains("net.l0.state") && err.contains("shape"), "{err}");
}

/// Rewrites the manifest (its hash is not checked: the tensor files stay consistent).
fn edit_manifest(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join(MANIFEST_FILE);
    let mut m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut m);
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
}

#[test]
fn inconsistent_manifest_is_an_error_not_a_later_panic() {
    let cases: [(&str, fn(&mut serde_json::Value)); 6] = [
        // The re-initialisation at the task's end would panic drawing from U(1, -1).
        ("init_bound", |m| m["networks"][0]["layers"][1]["init_bound"] = (-1.0).into()),
        // Fine-tuning a task that never finished (it has no mask to fine-tune).
        ("fine_tune", |m| m["networks"][0]["training"]["fine_tune"] = true.into()),
        // A finished task trained again as if new: its end would overwrite its mask.
        ("fine_tune", |m| m["networks"][0]["training"]["task"] = 0.into()),
        ("out of range", |m| m["networks"][0]["training"]["task"] = 7.into()),
        ("twice", |m| m["networks"][0]["finish_order"] = serde_json::json!([0, 1, 1])),
        ("no layers", |m| {
            m["networks"][0]["sizes"] = serde_json::json!([8]);
            m["networks"][0]["layers"] = serde_json::json!([]);
        }),
    ];
    for (needle, edit) in cases {
        let dir = tempfile::tempdir().unwrap();
        trained_policy(dir.path());
        edit_manifest(dir.path(), edit);
        let err = load_error(dir.path());
        assert!(err.contains(MANIFEST_FILE) && err.contains(needle), "expected {needle:?}: {err}");
    }
}

#[test]
fn saving_a_task_without_a_name_is_an_error_not_a_policy_that_cannot_load() {
    let mut net = small_mlp(&MaskConfig::default(), 3);
    net.begin_task(1, &[]).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let err = save_policy(dir.path(), &["none".into()], &[&net], &BTreeMap::new(), &serde_json::Value::Null).unwrap_err().to_string();
    assert!(err.contains("task 1") && err.contains("no name"), "{err}");
}

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
    let extras =
        BTreeMap::from([("action_std.0".to_string(), Tensor::from_vec(vec![0.5f32; OUT], OUT, &Device::Cpu).unwrap())]);
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
    type ManifestEdit = fn(&mut serde_json::Value);
    let cases: [(&str, ManifestEdit); 6] = [
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
    let err = save_policy(dir.path(), &["none".into()], &[&net], &BTreeMap::new(), &serde_json::Value::Null)
        .unwrap_err()
        .to_string();
    assert!(err.contains("task 1") && err.contains("no name"), "{err}");
}

/// The layer trains ln sigma and saves it as "{layer}.log_sigma" (restored exactly); a policy
/// written before that holds "{layer}.sigma" instead, which still loads (as its ln).
#[test]
fn log_sigma_round_trips_exactly_and_files_with_the_older_sigma_tensor_still_load() {
    let dir = tempfile::tempdir().unwrap();
    let net = trained_policy(dir.path());
    let loaded = load_policy(dir.path()).unwrap();
    for (a, b) in net.layers().iter().zip(loaded.network("net").unwrap().layers()) {
        assert_eq!(a.log_sigma().unwrap().to_bits(), b.log_sigma().unwrap().to_bits(), "{}", a.name());
    }

    // Rewrite model.safetensors the older way: "{layer}.sigma" = sigma, no "{layer}.log_sigma".
    let path = dir.path().join(MODEL_FILE);
    let bytes = std::fs::read(&path).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let mut owned: Vec<(String, safetensors::Dtype, Vec<usize>, Vec<u8>)> = Vec::new();
    for (name, t) in st.tensors() {
        match name.strip_suffix(".log_sigma") {
            Some(layer) => {
                let ln = f32::from_le_bytes(t.data().try_into().unwrap());
                owned.push((format!("{layer}.sigma"), t.dtype(), t.shape().to_vec(), ln.exp().to_le_bytes().to_vec()));
            }
            None => owned.push((name.clone(), t.dtype(), t.shape().to_vec(), t.data().to_vec())),
        }
    }
    let views: Vec<_> = owned
        .iter()
        .map(|(n, d, s, b)| (n.clone(), safetensors::tensor::TensorView::new(*d, s.clone(), b).unwrap()))
        .collect();
    let legacy = safetensors::serialize(views, None).unwrap();
    std::fs::write(&path, &legacy).unwrap();
    let (old_hash, new_hash) = (quadcl::util::sha256_hex(&bytes), quadcl::util::sha256_hex(&legacy));
    edit_manifest(dir.path(), |m| m["files"][MODEL_FILE] = serde_json::Value::String(new_hash.clone()));
    assert_ne!(old_hash, new_hash);

    let policy = load_policy(dir.path()).unwrap();
    for (a, b) in net.layers().iter().zip(policy.network("net").unwrap().layers()) {
        let (want, got) = (a.sigma().unwrap(), b.sigma().unwrap());
        assert!((got / want - 1.0).abs() < 1e-5, "{}: sigma {got} loaded from the older file, saved {want}", a.name());
    }
    // Without either tensor the error names the new one.
    let views: Vec<_> = owned
        .iter()
        .filter(|(n, ..)| !n.ends_with(".sigma"))
        .map(|(n, d, s, b)| (n.clone(), safetensors::tensor::TensorView::new(*d, s.clone(), b).unwrap()))
        .collect();
    let missing = safetensors::serialize(views, None).unwrap();
    std::fs::write(&path, &missing).unwrap();
    edit_manifest(dir.path(), |m| {
        m["files"][MODEL_FILE] = serde_json::Value::String(quadcl::util::sha256_hex(&missing))
    });
    let err = load_error(dir.path());
    assert!(err.contains("missing tensor net.l0.log_sigma"), "{err}");
}

#[test]
fn a_manifest_edited_after_it_was_written_is_an_error_not_a_different_policy() {
    type ManifestEdit = fn(&mut serde_json::Value);
    let cases: [ManifestEdit; 4] = [
        |m| m["tasks"][0] = "invert:RR".into(),
        |m| m["networks"][0]["mask"]["capacity"] = 0.5.into(),
        |m| m["config"] = serde_json::json!({"seed": 9}),
        |m| m["extras"] = serde_json::json!([]),
    ];
    for (i, edit) in cases.into_iter().enumerate() {
        let dir = tempfile::tempdir().unwrap();
        trained_policy(dir.path());
        load_policy(dir.path()).unwrap();
        edit_manifest(dir.path(), edit);
        let err = load_error(dir.path());
        assert!(err.contains(MANIFEST_FILE) && err.contains("changed after it was written"), "case {i}: {err}");
    }
    // Rewriting the same content in another layout is not an edit.
    let dir = tempfile::tempdir().unwrap();
    trained_policy(dir.path());
    edit_manifest(dir.path(), |_| {});
    load_policy(dir.path()).unwrap();
}

#[test]
fn a_stamped_provenance_reads_back_and_leaves_the_policy_loadable_and_its_tensors_unchanged() {
    use quadcl::nn::checkpoint::{read_provenance, write_provenance};
    let dir = tempfile::tempdir().unwrap();
    trained_policy(dir.path());
    assert_eq!(read_provenance(dir.path()).unwrap(), None, "a policy written before provenance has none");
    let model = std::fs::read(dir.path().join(MODEL_FILE)).unwrap();
    let provenance = quadcl::util::Provenance::of_this_build(Some(b"seed = 11\n"));
    write_provenance(dir.path(), &provenance).unwrap();
    assert_eq!(read_provenance(dir.path()).unwrap(), Some(provenance));
    // Outside the manifest's content digest: the policy still loads, its tensor file untouched.
    assert_eq!(load_policy(dir.path()).unwrap().tasks.len(), 3);
    assert_eq!(std::fs::read(dir.path().join(MODEL_FILE)).unwrap(), model);
    // Any other edit of the manifest is still refused.
    let path = dir.path().join(MANIFEST_FILE);
    let edited = std::fs::read_to_string(&path).unwrap().replace("crash:FL", "crash:FR");
    std::fs::write(&path, edited).unwrap();
    assert!(load_error(dir.path()).contains("changed after it was written"));
}

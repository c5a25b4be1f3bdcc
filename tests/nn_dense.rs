//! The dense network of the baselines: a masked policy becomes its dense
//! equivalent without changing any output, a new task's head starts from the
//! last task's, the trunk is shared and trains for every task, and a policy
//! directory keeps trunk and heads exactly.

use candle_core::{Device, Tensor};
use quadcl::nn::{load_policy, save_policy, Activation, DenseMlp, MaskConfig, MaskedMlp, Network};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

fn input(rows: usize, cols: usize, seed: u64) -> Tensor {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let v: Vec<f32> = (0..rows * cols).map(|_| rand::Rng::gen_range(&mut rng, -1.0f32..1.0)).collect();
    Tensor::from_vec(v, (rows, cols), &Device::Cpu).unwrap()
}

fn values(t: &Tensor) -> Vec<f32> {
    t.flatten_all().unwrap().to_vec1().unwrap()
}

/// A masked network that learned tasks 0 and 1 (a few steps each moving its weights).
fn masked_with_two_tasks() -> MaskedMlp {
    let mut net = MaskedMlp::new("actor", &[6, 16, 8, 3], Activation::Elu, &MaskConfig::default(), 5).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for task in 0..2 {
        net.begin_task(task, &[]).unwrap();
        net.begin_iteration(0, &mut rng).unwrap();
        let loss = net.forward(&input(4, 6, task as u64)).unwrap().sqr().unwrap().sum_all().unwrap();
        let grads = loss.backward().unwrap();
        let mut adam = quadcl::nn::MaskedAdam::new(Default::default());
        adam.step(&net.params(), &grads).unwrap();
        net.end_task(&mut rng).unwrap();
    }
    net
}

#[test]
fn a_masked_network_as_dense_recalls_the_trunk_task_bit_identically() {
    let masked = masked_with_two_tasks();
    let x = input(5, 6, 9);
    let dense = DenseMlp::from_masked(&masked, Some(1)).unwrap();
    assert_eq!(values(&dense.forward_task(1, &x).unwrap()), values(&masked.forward_task(1, &x).unwrap()));
    // Task 0 keeps its own head on task 1's trunk: not task 0's masked output any more.
    assert_ne!(values(&dense.forward_task(0, &x).unwrap()), values(&masked.forward_task(0, &x).unwrap()));
    assert_eq!(dense.finished_tasks(), &[0, 1]);
}

#[test]
fn a_new_task_starts_from_the_last_heads_copy_and_every_task_trains_the_shared_trunk() {
    let mut net = DenseMlp::new("actor", &[6, 16, 3], Activation::Elu, 2).unwrap();
    let x = input(4, 6, 3);
    let mut adam = quadcl::nn::MaskedAdam::new(Default::default());
    let mut trunk_before = net.trunk_values().unwrap();
    for task in 0..2 {
        net.begin_task(task).unwrap();
        if task == 1 {
            // The head is a copy of task 0's: the same outputs before any step.
            assert_eq!(values(&net.forward(&x).unwrap()), values(&net.forward_task(0, &x).unwrap()));
        }
        let names: Vec<String> = net.params().iter().map(|p| p.name.clone()).collect();
        assert_eq!(names, ["actor.l0.weight", "actor.l0.bias", "actor.head.weight", "actor.head.bias"]);
        let grads = net.forward(&x).unwrap().sqr().unwrap().sum_all().unwrap().backward().unwrap();
        adam.step(&net.params(), &grads).unwrap();
        net.end_task().unwrap();
        let trunk = net.trunk_values().unwrap();
        assert_ne!(trunk, trunk_before, "task {task} did not move the trunk");
        trunk_before = trunk;
    }
    // Task 1's step moved its own head only: task 0's head is what task 0 left.
    assert_ne!(values(&net.forward_task(0, &x).unwrap()), values(&net.forward_task(1, &x).unwrap()));
    assert!(net.params().is_empty(), "nothing trains between tasks");
}

#[test]
fn a_dense_policy_directory_keeps_trunk_heads_and_the_task_in_progress() {
    let mut net = DenseMlp::from_masked(&masked_with_two_tasks(), Some(1)).unwrap();
    net.begin_task(2).unwrap();
    let masked = masked_with_two_tasks();
    let dir = tempfile::tempdir().unwrap();
    let tasks: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
    let mut renamed = MaskedMlp::new("critic", &[6, 4, 1], Activation::Elu, &MaskConfig::default(), 1).unwrap();
    renamed.begin_task(0, &[]).unwrap();
    save_policy(dir.path(), &tasks, &[&net, &renamed], &BTreeMap::new(), &serde_json::json!({})).unwrap();
    let mut policy = load_policy(dir.path()).unwrap();
    let Network::Dense(loaded) = policy.take_network("actor", dir.path()).unwrap() else { panic!("not dense") };
    let x = input(3, 6, 4);
    for t in 0..3 {
        assert_eq!(values(&loaded.forward_task(t, &x).unwrap()), values(&net.forward_task(t, &x).unwrap()));
    }
    assert_eq!((loaded.current_task(), loaded.finished_tasks()), (Some(2), &[0usize, 1][..]));
    assert!(policy.network("critic").is_ok(), "the masked network is still there");
    assert_eq!(values(&loaded.forward_task(1, &x).unwrap()), values(&masked.forward_task(1, &x).unwrap()));
}

#[test]
fn a_dense_manifest_that_names_a_task_without_a_head_is_an_error_naming_the_file() {
    let mut net = DenseMlp::new("actor", &[4, 8, 2], Activation::Elu, 0).unwrap();
    net.begin_task(0).unwrap();
    net.end_task().unwrap();
    let dir = tempfile::tempdir().unwrap();
    save_policy(dir.path(), &["a".into()], &[&net], &BTreeMap::new(), &serde_json::json!({})).unwrap();
    let manifest = dir.path().join("manifest.json");
    let text = std::fs::read_to_string(&manifest).unwrap();
    std::fs::write(&manifest, text.replace("\"heads\": [\n        0\n      ]", "\"heads\": []")).unwrap();
    assert_ne!(std::fs::read_to_string(&manifest).unwrap(), text, "the edit applied");
    let err = format!("{:#}", load_policy(dir.path()).unwrap_err());
    assert!(err.contains("manifest.json") && err.contains("head"), "{err}");
}

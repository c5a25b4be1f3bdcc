//! Exact recall on the sequence paths the network-level recall tests do not
//! cover (issue 13 item 4), on the toy learner through the whole engine: every
//! finished task's evaluation after the last step is bit-identical to its
//! evaluation right after it was learned, with per-task capacity and lambda
//! changes, related tasks, a base whose private share was 0, and a capacity
//! that exhausts the vacant weights.

use quadcl::engine::MetricsFile;
use quadcl::headless::{run, RunOptions};

/// Runs `text` and checks that every task's evaluation never changed after it was learned.
fn assert_exact_recall(text: &str) -> MetricsFile {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, text).unwrap();
    let m = run(&cfg, &tmp.path().join("out"), RunOptions::default()).unwrap();
    assert_eq!(m.completed_steps, m.total_steps);
    assert_eq!(m.summary.forgetting, Some(0.0));
    for (step, record) in m.steps.iter().enumerate() {
        let learned = m.evaluations[step].iter().find(|e| e.report.task == record.name).unwrap();
        for later in &m.evaluations[step..] {
            let again = later.iter().find(|e| e.report.task == record.name).unwrap();
            assert_eq!(again, learned, "{} after a later step", record.name);
        }
    }
    m
}

const HEAD: &str = "seed = 5\niterations = 6\n[run]\nlearner = \"toy\"\n[net.mask]\nentropy_iterations = 3\n";

#[test]
fn recall_stays_exact_when_capacity_and_lambda_change_per_task_and_tasks_name_related_ones() {
    let text = format!(
        "{HEAD}[[task]]\nname = \"crash:FL\"\n[task.switches]\ncapacity = 0.4\nlambda = \"0.5\"\n\
         [[task]]\nname = \"invert:RR\"\nrelated = [\"crash:FL\"]\n[task.switches]\ncapacity = 0.1\nlambda = \"free\"\n\
         [[task]]\nname = \"noise:FR\"\nrelated = [\"crash:FL\", \"invert:RR\"]\n[task.switches]\nlambda = \"vacant\"\nprivate_share = 0.1\n\
         [[task]]\nname = \"crash:RL\"\n[task.switches]\nlambda = \"per-layer\"\nreinit = false\n"
    );
    let m = assert_exact_recall(&text);
    assert_eq!(m.steps[1].related, vec![0]);
}

#[test]
fn recall_stays_exact_after_a_task_ends_with_private_share_zero() {
    let text = format!(
        "{HEAD}[[task]]\nname = \"crash:FL\"\n[task.switches]\nprivate_share = 0.0\n\
         [[task]]\nname = \"invert:RR\"\nrelated = [\"crash:FL\"]\n[task.switches]\ncapacity = 0.5\nlambda = \"0.1\"\n\
         [[task]]\nname = \"noise:FR\"\nrelated = [\"crash:FL\"]\n"
    );
    assert_exact_recall(&text);
}

#[test]
fn recall_stays_exact_when_the_vacant_weights_run_out() {
    // Capacity 0.6 with 0.9 of each row from vacant weights: after two tasks few vacant
    // elements are left, so later tasks fill their quota from occupied ones.
    let text = format!(
        "{HEAD}[method]\ncapacity = 0.6\nlambda = \"0.9\"\nprivate_share = 0.1\n\
         [[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"noise:FR\"\n[[task]]\nname = \"crash:RL\"\n"
    );
    let m = assert_exact_recall(&text);
    // ... and the records say so: the vacant share falls to 0 and later tasks reuse more.
    let capacity: Vec<_> =
        m.steps.iter().map(|s| s.capacity.clone().expect("a masked step records its capacity")).collect();
    assert!(capacity.windows(2).all(|w| w[1].vacant_share_after <= w[0].vacant_share_after));
    assert_eq!(capacity[0].from_occupied_share, 0.0, "the first task has nothing to reuse");
    let last = capacity.last().unwrap();
    assert!(!last.exhausted_layers.is_empty() && last.vacant_share_after < 0.05, "{last:?}");
    assert!(last.from_occupied_share > capacity[1].from_occupied_share, "{capacity:?}");
}

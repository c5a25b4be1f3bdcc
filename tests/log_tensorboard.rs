//! TensorBoard events and CSV beside a run's results (`OUT/tb/`): `quadcl run` on the
//! toy learner writes one folder per task and one for the sequence whose scalars are
//! the curves of `metrics.json`, and a run stopped and resumed reads back, as
//! TensorBoard reads it (events after a session START at step S replace the earlier
//! files' from S on), the same as a run that never stopped.

use quadcl::headless::{run, RunOptions};
use quadcl::log::{read_dir_scalars, EventFile, CSV_FILE};
use std::collections::BTreeMap;
use std::path::Path;

const RUN: &str = "seed = 11\niterations = 5\n[run]\nlearner = \"toy\"\n[net.mask]\nentropy_iterations = 2\n\
[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\niterations = 7\n[[task]]\nname = \"noise:FR\"\n";

/// A folder's scalars by tag as TensorBoard keeps them: (step, value) in step order.
fn as_tensorboard_reads(files: &[EventFile]) -> BTreeMap<String, Vec<(i64, f32)>> {
    let mut by_tag: BTreeMap<String, Vec<(i64, f32)>> = BTreeMap::new();
    for file in files {
        for &start in &file.session_starts {
            by_tag.values_mut().for_each(|v| v.retain(|(s, _)| *s < start));
        }
        for (step, tag, value) in &file.scalars {
            by_tag.entry(tag.clone()).or_default().push((*step, *value));
        }
    }
    by_tag
}

fn tb(out: &Path, folder: &str) -> BTreeMap<String, Vec<(i64, f32)>> {
    as_tensorboard_reads(&read_dir_scalars(&out.join("tb").join(folder)).unwrap())
}

#[test]
fn a_run_writes_each_tasks_curves_and_the_sequence_as_tensorboard_scalars_and_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, RUN).unwrap();
    let out = tmp.path().join("out");
    run(&cfg, &out, RunOptions::default()).unwrap();
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let mut sequence_perf = Vec::new();
    for (i, folder) in ["00-crash_FL", "01-invert_RR", "02-noise_FR"].iter().enumerate() {
        let curve: Vec<f32> = metrics["curves"][i]["performance"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        let scalars = tb(&out, folder);
        let perf = &scalars["charts/performance"];
        assert_eq!(perf.iter().map(|(_, v)| *v).collect::<Vec<_>>(), curve, "{folder}");
        assert_eq!(perf.iter().map(|(s, _)| *s).collect::<Vec<_>>(), (1..=curve.len() as i64).collect::<Vec<_>>());
        let csv = std::fs::read_to_string(out.join("tb").join(folder).join(CSV_FILE)).unwrap();
        assert_eq!(csv.lines().filter(|l| l.contains(",charts/performance,")).count(), curve.len(), "{folder}");
        sequence_perf.extend(curve);
    }
    let sequence = tb(&out, "sequence");
    let perf: Vec<(i64, f32)> = sequence["charts/performance"].clone();
    assert_eq!(perf.iter().map(|(_, v)| *v).collect::<Vec<_>>(), sequence_perf);
    assert_eq!(perf.last().unwrap().0, 17, "5 + 7 + 5 iterations on one axis");
    let average = sequence["eval/average_performance"].last().unwrap().1;
    assert_eq!(average, metrics["average_performance"].as_f64().unwrap() as f32);
    assert_eq!(sequence["eval/average_performance"].len(), 3, "the measures after each task");
    assert_eq!(sequence["eval/forgetting"].len(), 2, "forgetting from the second task on");
    assert!(sequence.contains_key("eval/crash:FL/fall_rate"));
}

#[test]
fn a_resumed_run_reads_back_as_the_run_that_never_stopped() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, RUN).unwrap();
    let whole = tmp.path().join("whole");
    run(&cfg, &whole, RunOptions::default()).unwrap();
    let parts = tmp.path().join("parts");
    run(&cfg, &parts, RunOptions { stop_after: Some(1), ..Default::default() }).unwrap();
    run(&cfg, &parts, RunOptions { resume: true, ..Default::default() }).unwrap();
    // Wall times and SPS differ between the runs; everything else is the same.
    let values = |out: &Path, folder: &str| {
        let mut t = tb(out, folder);
        t.retain(|tag, _| !tag.starts_with("time/") && tag != "charts/SPS");
        t
    };
    for folder in ["sequence", "00-crash_FL", "01-invert_RR", "02-noise_FR"] {
        assert_eq!(values(&parts, folder), values(&whole, folder), "{folder}");
    }
    let csv_steps = |out: &Path| -> Vec<String> {
        let text = std::fs::read_to_string(out.join("tb/sequence").join(CSV_FILE)).unwrap();
        text.lines()
            .filter(|l| l.contains(",charts/performance,"))
            .map(|l| l.split(',').next().unwrap().to_string())
            .collect()
    };
    assert_eq!(csv_steps(&parts), csv_steps(&whole));
    // Without TensorBoard, no tb/ at all.
    let quiet = tmp.path().join("quiet");
    run(&cfg, &quiet, RunOptions { no_tensorboard: true, ..Default::default() }).unwrap();
    assert!(!quiet.join("tb").exists());
}

#[test]
fn a_task_whose_folder_cannot_be_written_files_no_curve_under_another_task() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, RUN).unwrap();
    let out = tmp.path().join("out");
    // A file in the way of the second task's folder.
    std::fs::create_dir_all(out.join("tb")).unwrap();
    std::fs::write(out.join("tb/01-invert_RR"), "in the way").unwrap();
    let m = run(&cfg, &out, RunOptions::default()).unwrap();
    assert_eq!(m.completed_steps, 3, "training goes on");
    for (folder, iterations) in [("00-crash_FL", 5), ("02-noise_FR", 5)] {
        let perf = &tb(&out, folder)["charts/performance"];
        let steps: Vec<i64> = perf.iter().map(|(s, _)| *s).collect();
        assert_eq!(steps, (1..=iterations).collect::<Vec<_>>(), "{folder} holds its own task's iterations only");
        let csv = std::fs::read_to_string(out.join("tb").join(folder).join(CSV_FILE)).unwrap();
        assert_eq!(csv.lines().filter(|l| l.contains(",charts/performance,")).count(), iterations as usize);
    }
    assert_eq!(std::fs::read_to_string(out.join("tb/01-invert_RR")).unwrap(), "in the way");
    // The sequence's curves go on through all three tasks.
    assert_eq!(tb(&out, "sequence")["charts/performance"].last().unwrap().0, 17);
}

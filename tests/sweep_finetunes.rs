//! `quadcl sweep finetunes DIR` on folders of fine-tuning reports built here: each
//! task before and after over the seeds, the fine-tuned task's change paired within
//! each seed with its interval in closed form (values {x, x, y}: [x, x + 2 (y - x) / 3]),
//! seed folders in natural order, another task that changed named, and reports of
//! different fine-tunings, or none at all, as errors naming the files.

use quadcl::engine::{Evaluation, Shift, Sim2RealReport};
use quadcl::rl::EvalReport;
use quadcl::sweep::finetunes::{FINETUNES_JSON, FINETUNES_MD};
use quadcl::sweep::{finetunes, finetunes_markdown, Finetunes};
use std::process::Command;

const TASKS: [&str; 3] = ["none", "crash:FL", "invert:RL"];

fn evaluation(task: &str, performance: f64, fall_rate: f64) -> Evaluation {
    Evaluation {
        report: EvalReport {
            task: task.to_string(),
            episodes: 32,
            mean_return: 30.0 * performance,
            lin_vel_err: 0.2,
            ang_vel_err: 0.3,
            fall_rate,
            survival_s: 18.0,
            return_std: Some(1.0),
            seed: 7,
            physics_resets: 0,
        },
        performance,
    }
}

fn shift() -> Shift {
    Shift {
        friction: Some([0.3, 0.5]),
        added_mass: Some([1.0, 3.0]),
        latency_s: 0.02,
        iterations: 200,
        ..Shift::default()
    }
}

/// A report fine-tuning `task` from `before` to `after` (its performance); every other task
/// keeps performance 0.5, but `invert:RL` moves to `other_after` when given.
fn report(task: &str, before: f64, after: f64, other_after: Option<f64>) -> Sim2RealReport {
    let side = |fine_tuned: f64, last: f64| {
        TASKS
            .iter()
            .map(|t| match *t {
                t if t == task => evaluation(t, fine_tuned, 0.25),
                "invert:RL" => evaluation("invert:RL", last, 0.1),
                t => evaluation(t, 0.5, 0.1),
            })
            .collect::<Vec<_>>()
    };
    Sim2RealReport {
        task: task.to_string(),
        shift: shift(),
        iterations: 200,
        before: side(before, 0.5),
        after: side(after, other_after.unwrap_or(0.5)),
        changed_other_tasks: Vec::new(),
        curve: vec![before, after],
    }
}

fn folder(reports: &[(&str, Sim2RealReport)]) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    for (name, r) in reports {
        let dir = tmp.path().join(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("finetune.json"), serde_json::to_string_pretty(r).unwrap()).unwrap();
    }
    tmp
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

#[test]
fn each_task_before_and_after_is_paired_within_seeds_in_their_natural_order() {
    // seed10 sorts after seed2; crash:FL gains 0.1, 0.1 and 0.4.
    let tmp = folder(&[
        ("seed10", report("crash:FL", 0.2, 0.6, None)),
        ("seed1", report("crash:FL", 0.3, 0.4, None)),
        ("seed2", report("crash:FL", 0.4, 0.5, None)),
    ]);
    let table = finetunes(tmp.path()).unwrap();
    assert_eq!(table.seeds, ["seed1", "seed2", "seed10"]);
    let tuned = &table.tasks[1];
    assert!(tuned.fine_tuned && tuned.changed_at == ["seed1", "seed2", "seed10"]);
    let d = tuned.performance.after_minus_before;
    assert!(close(d.mean, 0.2) && close(d.low, 0.1) && close(d.high, 0.3), "{d:?}");
    assert_eq!(tuned.performance.per_seed, [(0.3, 0.4), (0.4, 0.5), (0.2, 0.6)]);
    assert!(table.tasks.iter().filter(|t| !t.fine_tuned).all(|t| t.changed_at.is_empty()));
    assert_eq!(table.fine_tuned_measures[1].0, "fall rate");
    assert!(close(table.fine_tuned_measures[1].1.after_minus_before.mean, 0.0));

    let md = finetunes_markdown(&table);
    assert!(md.contains("friction 0.3-0.5, added mass 1-3 kg, latency 0.02 s; 200 iterations"), "{md}");
    let row = md.lines().find(|l| l.starts_with("| crash:FL (fine-tuned)")).unwrap();
    assert!(row.contains("0.200 [0.100, 0.300]") && row.contains("0/3 seeds (changed: seed1, seed2, seed10)"), "{row}");
    assert!(md.contains("Every other task's evaluation is the same before and after, at every seed."));
    let perf = md.lines().find(|l| l.starts_with("| performance")).unwrap();
    assert!(perf.contains("| 0.300 -> 0.400 | 0.400 -> 0.500 | 0.200 -> 0.600 |"), "{perf}");
}

#[test]
fn another_task_that_changed_is_named_with_its_seeds() {
    let tmp =
        folder(&[("seed1", report("crash:FL", 0.3, 0.4, None)), ("seed2", report("crash:FL", 0.3, 0.4, Some(0.45)))]);
    let table = finetunes(tmp.path()).unwrap();
    assert_eq!(table.tasks[2].changed_at, ["seed2"]);
    let md = finetunes_markdown(&table);
    assert!(md.contains("| invert:RL ") && md.contains("1/2 seeds (changed: seed2)"), "{md}");
    assert!(md.contains("Other tasks whose evaluation changed: invert:RL"), "{md}");
}

#[test]
fn reports_of_different_fine_tunings_or_none_are_errors_naming_the_files() {
    let tmp = folder(&[("seed1", report("crash:FL", 0.3, 0.4, None)), ("seed2", report("invert:RL", 0.3, 0.4, None))]);
    let err = format!("{:#}", finetunes(tmp.path()).unwrap_err());
    assert!(err.contains("seed1/finetune.json") && err.contains("seed2/finetune.json"), "{err}");

    let mut shifted = report("crash:FL", 0.3, 0.4, None);
    shifted.shift.latency_s = 0.04;
    let tmp = folder(&[("seed1", report("crash:FL", 0.3, 0.4, None)), ("seed2", shifted)]);
    assert!(finetunes(tmp.path()).is_err());

    let empty = tempfile::tempdir().unwrap();
    std::fs::create_dir(empty.path().join("seed1")).unwrap();
    let err = format!("{:#}", finetunes(empty.path()).unwrap_err());
    assert!(err.contains("no fine-tuning report") && err.contains(&empty.path().display().to_string()), "{err}");

    let broken = tempfile::tempdir().unwrap();
    std::fs::create_dir(broken.path().join("seed1")).unwrap();
    std::fs::write(broken.path().join("seed1/finetune.json"), "{\"task\": 3}").unwrap();
    let err = format!("{:#}", finetunes(broken.path()).unwrap_err());
    assert!(err.contains("seed1/finetune.json") && err.contains("not a report of `quadcl finetune`"), "{err}");
}

#[test]
fn the_command_writes_what_it_prints() {
    let tmp = folder(&[("seed1", report("crash:FL", 0.3, 0.4, None)), ("seed2", report("crash:FL", 0.2, 0.5, None))]);
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl")).args(["sweep", "finetunes"]).arg(tmp.path()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let md = std::fs::read_to_string(tmp.path().join(FINETUNES_MD)).unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains(&md));
    let json: Finetunes =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join(FINETUNES_JSON)).unwrap()).unwrap();
    assert_eq!(json, finetunes(tmp.path()).unwrap());
}

#[test]
fn the_figure_draws_each_seeds_before_and_after_with_the_fine_tuned_task_in_its_own_colour() {
    let tmp = folder(&[
        ("seed1", report("crash:FL", 0.2, 0.8, None)),
        ("seed2", report("crash:FL", 0.3, 0.7, None)),
        ("seed3", report("crash:FL", 0.1, 0.9, None)),
    ]);
    let png = quadcl::plot::finetunes_png(&finetunes(tmp.path()).unwrap()).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(png)).read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut rgb).unwrap();
    assert_eq!(info.width as usize, 140 + 78 * TASKS.len());
    // The fine-tuned task's dots (orange) and the other tasks' afters (blue) are both drawn.
    let count = |c: [u8; 3]| rgb.chunks(3).filter(|p| *p == c).count();
    assert!(count([255, 127, 14]) > 20, "orange: the fine-tuned task after");
    assert!(count([31, 119, 180]) > 20, "blue: the other tasks after");
}

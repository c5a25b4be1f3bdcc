//! `quadcl sweep local` through the binary, on a 2 x 2 sweep (capacity x seed) of a toy
//! run: killed with SIGKILL part-way and run again, it resumes the stopped cells and
//! collects into the same table as a sweep that ran uninterrupted, and every cell's
//! metrics.json is the same (provenance aside) whatever --jobs and threads it ran with; two
//! `sweep local` started together on one folder train each cell once between them.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

const RUN: &str = "seed = 1\niterations = 1500\n[run]\nlearner = \"toy\"\n[eval]\nepisodes = 1\n\
                   [[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"noise:FR\"\n";
const SWEEP: &str = "base = \"toy.toml\"\n[axes]\nseed = [1, 2]\n\"net.mask.capacity\" = [0.2, 0.3]\n";

fn quadcl(args: &[&str], dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl")).args(args).arg(dir).output().unwrap();
    assert!(out.status.success(), "quadcl {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A folder holding the toy run file and the 2 x 2 sweep over it.
fn toy_sweep() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("toy.toml"), RUN).unwrap();
    std::fs::write(tmp.path().join("sweep.toml"), SWEEP).unwrap();
    tmp
}

fn plan(tmp: &Path, name: &str) -> std::path::PathBuf {
    let dir = tmp.join(name);
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["sweep", "plan"])
        .arg(tmp.join("sweep.toml"))
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    dir
}

/// A cell's metrics.json without its provenance (which records the threads it ran with).
fn results(dir: &Path, cell: usize) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join(format!("runs/{cell}/metrics.json"))).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let provenance = v.as_object_mut().unwrap().remove("provenance");
    assert!(provenance.is_some_and(|p| p["run_file_sha256"].is_string()), "cell {cell} records its provenance");
    v
}

fn completed(dir: &Path, cell: usize) -> usize {
    std::fs::read_to_string(dir.join(format!("runs/{cell}/metrics.json")))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["completed_steps"].as_u64())
        .unwrap_or(0) as usize
}

#[test]
fn a_sweep_killed_and_run_again_collects_the_same_table_as_an_uninterrupted_one() {
    let tmp = toy_sweep();

    let whole = plan(tmp.path(), "whole");
    quadcl(&["sweep", "local", "--jobs", "1"], &whole);
    quadcl(&["sweep", "collect"], &whole);

    let killed = plan(tmp.path(), "killed");
    let mut sweep = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["sweep", "local", "--jobs", "2", "--threads-per-job", "1"])
        .arg(&killed)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while (0..4).all(|c| completed(&killed, c) == 0) {
        assert!(start.elapsed() < Duration::from_secs(120), "no cell finished a task in 2 minutes");
        std::thread::sleep(Duration::from_millis(10));
    }
    sweep.kill().unwrap(); // SIGKILL
    sweep.wait().unwrap();
    let done: Vec<usize> = (0..4).map(|c| completed(&killed, c)).collect();
    assert!(done.iter().sum::<usize>() < 12, "the kill came after every cell had finished: {done:?}");
    // The cells' runs die with the sweep: within a moment none is running and some are unfinished.
    let start = Instant::now();
    loop {
        let status: serde_json::Value = serde_json::from_str(&quadcl(&["sweep", "status", "--json"], &killed)).unwrap();
        let states: Vec<&str> = status.as_array().unwrap().iter().map(|c| c["state"].as_str().unwrap()).collect();
        if !states.contains(&"running") {
            assert!(states.iter().any(|s| *s == "stopped" || *s == "pending"), "{states:?}");
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "cells still running after the sweep was killed: {states:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }

    let report = quadcl(&["sweep", "local", "--jobs", "2"], &killed);
    assert!(report.contains("finished now"), "{report}");
    quadcl(&["sweep", "collect"], &killed);
    for file in ["collected.json", "collected.md"] {
        let (a, b) = (std::fs::read(whole.join(file)).unwrap(), std::fs::read(killed.join(file)).unwrap());
        assert!(a == b, "{file} differs:\n{}\n{}", String::from_utf8_lossy(&a), String::from_utf8_lossy(&b));
    }
    for cell in 0..4 {
        assert_eq!(results(&whole, cell), results(&killed, cell), "cell {cell}");
    }
    let table: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(killed.join("collected.json")).unwrap()).unwrap();
    assert_eq!(table["groups"].as_array().unwrap().len(), 2);
    assert_eq!(table["groups"][0]["finished"], 2);
    // Nothing left to do: a third run trains nothing.
    let again = quadcl(&["sweep", "local"], &killed);
    assert!(again.contains("0 cells finished now, 4 before"), "{again}");
}

#[test]
fn two_sweeps_on_one_folder_share_its_cells_and_train_each_once() {
    let tmp = toy_sweep();
    let dir = plan(tmp.path(), "shared");
    // Started together: each lists cells as to train that the other then starts.
    let sweeps: Vec<std::process::Child> = (0..2)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_quadcl"))
                .args(["sweep", "local", "--jobs", "1", "--threads-per-job", "1"])
                .arg(&dir)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut finished_now = 0;
    for sweep in sweeps {
        let out = sweep.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let report = String::from_utf8_lossy(&out.stdout).into_owned();
        finished_now += report.split(" cells finished now").next().unwrap().trim().parse::<usize>().unwrap();
    }
    assert_eq!(finished_now, 4, "each cell finished by one of the two");
    for cell in 0..4 {
        let log = std::fs::read_to_string(dir.join(format!("logs/{cell}.log"))).unwrap();
        assert_eq!(log.matches("== quadcl sweep local: cell").count(), 1, "cell {cell} started once:\n{log}");
        assert_eq!(completed(&dir, cell), 3, "cell {cell}");
    }
    let again = quadcl(&["sweep", "local"], &dir);
    assert!(again.contains("0 cells finished now, 4 before"), "{again}");
}

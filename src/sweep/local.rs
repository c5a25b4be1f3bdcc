//! Running a sweep on this machine (`quadcl sweep local DIR [--jobs N]`): every
//! cell that has not finished is trained by a child process,
//! `quadcl run --config cells/I.toml --out runs/I --resume`, at most `jobs` at a
//! time, each with `RAYON_NUM_THREADS` set to its share of the cores, its output
//! appended to `logs/I.log`. A cell stopped half-way (the sweep was killed, the
//! machine went down) is resumed from its last completed task; a run is
//! deterministic whatever its thread count, so the collected table is the same
//! however the sweep was run and interrupted.
//!
//! Every cell's run file is checked (against the plan's hash, and as a run
//! file) before any starts. A child dies with the sweep (Linux: its parent-death
//! signal), so a killed sweep leaves no orphan writing into a run folder; a cell
//! whose marker names a live process (another `sweep local`) is left to it.
//! Several `sweep local` on one folder and machine share its cells: each checks a
//! cell again under the folder's claim lock just before starting it, so none starts
//! a cell another has started or finished since, and each runs until no cell is
//! left; a cell's marker is changed at its end only while it still names that run.

use super::collect::{read_cell, RunMeasures};
use super::marker::{claim_lock, read_marker, running_elsewhere, write_marker, Marker};
use super::plan::{Cell, Plan};
use super::status::cell_finished;
use super::LOGS_DIR;
use crate::util::hostname;
use crate::util::text::one_line;
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How a local sweep runs.
#[derive(Debug, Clone)]
pub struct LocalOptions {
    /// Cells trained at the same time.
    pub jobs: usize,
    /// Worker threads of each (`RAYON_NUM_THREADS`).
    pub threads_per_job: usize,
    /// The quadcl binary that trains a cell (the running one).
    pub quadcl: PathBuf,
}

impl LocalOptions {
    /// `jobs` at a time sharing this machine's cores (at least one thread each).
    pub fn sharing_cores(jobs: usize, quadcl: PathBuf) -> Self {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let jobs = jobs.max(1);
        Self { jobs, threads_per_job: (cores / jobs).max(1), quadcl }
    }
}

/// What a local sweep did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LocalReport {
    /// Cells that finished now.
    pub finished: Vec<usize>,
    /// Cells that had finished before.
    pub already_finished: Vec<usize>,
    /// Cells whose run failed.
    pub failed: Vec<usize>,
    /// Cells left to another live runner: running in another process when this one
    /// reached them, or finished by it meanwhile.
    pub running_elsewhere: Vec<usize>,
}

/// A cell being trained.
struct Running {
    index: usize,
    child: Child,
    started: Instant,
}

/// Runs the sweep in `dir` to the end (see the module doc); `say` gets one line per event.
pub fn run_local(dir: &Path, options: &LocalOptions, say: &mut dyn FnMut(&str)) -> anyhow::Result<LocalReport> {
    let dir = std::path::absolute(dir).with_context(|| format!("{}: no absolute path", dir.display()))?;
    let plan = Plan::load(&dir)?;
    plan.check_cells(&dir)?;
    std::fs::create_dir_all(dir.join(LOGS_DIR))
        .with_context(|| format!("creating {}", dir.join(LOGS_DIR).display()))?;
    let mut report = LocalReport::default();
    let mut todo: Vec<&Cell> = Vec::new();
    for cell in &plan.cells {
        let found = read_cell(&dir, cell).run::<RunMeasures>(&dir, cell);
        if found.as_ref().is_ok_and(|run| run.as_ref().is_some_and(|m| m.finished())) {
            report.already_finished.push(cell.index);
        } else if let Err(why) = found {
            // Training it would have to resume another run: the folder is left as it is.
            say(&format!("{why}; not trained: move {} away to train the cell", dir.join(&cell.run).display()));
            report.failed.push(cell.index);
        } else if running_elsewhere(&dir, cell) {
            say(&format!(
                "cell {} ({}): already running in another process, left to it",
                cell.index,
                one_line(&cell.name)
            ));
            report.running_elsewhere.push(cell.index);
        } else {
            todo.push(cell);
        }
    }
    say(&format!(
        "{} cells: {} finished before, {} to train, {} at a time with {} threads each",
        plan.cells.len(),
        report.already_finished.len(),
        todo.len(),
        options.jobs,
        options.threads_per_job
    ));
    todo.reverse();
    let mut running: Vec<Running> = Vec::new();
    while !todo.is_empty() || !running.is_empty() {
        while running.len() < options.jobs.max(1) {
            let Some(cell) = todo.pop() else { break };
            // Another `sweep local` on this folder may have taken the cell since the list was
            // made: the check and the start happen under the folder's claim lock.
            let _claim = claim_lock(&dir)?;
            if cell_finished(&dir, cell) || running_elsewhere(&dir, cell) {
                say(&format!("cell {} ({}): taken by another process, left to it", cell.index, one_line(&cell.name)));
                report.running_elsewhere.push(cell.index);
                continue;
            }
            let child = spawn_cell(&dir, cell, options)?;
            write_marker(&dir, cell.index, Some(&Marker::Running { pid: child.id(), host: hostname() }))?;
            say(&format!("cell {} ({}): started", cell.index, one_line(&cell.name)));
            running.push(Running { index: cell.index, child, started: Instant::now() });
        }
        std::thread::sleep(Duration::from_millis(50));
        let mut i = 0;
        while i < running.len() {
            let Some(status) = running[i].child.try_wait().context("waiting for a cell's run")? else {
                i += 1;
                continue;
            };
            let done = running.swap_remove(i);
            let cell = &plan.cells[done.index];
            let secs = done.started.elapsed().as_secs_f64();
            // The marker is ours to change only while it still names this run: once the run
            // ended, another `sweep local` may have started the cell again (a failed one).
            let _claim = claim_lock(&dir)?;
            let ours = read_marker(&dir, cell.index)
                .is_some_and(|m| m == Marker::Running { pid: done.child.id(), host: hostname() });
            if status.success() && cell_finished(&dir, cell) {
                if ours {
                    write_marker(&dir, cell.index, None)?;
                }
                say(&format!("cell {} ({}): finished in {secs:.1} s", cell.index, one_line(&cell.name)));
                report.finished.push(cell.index);
            } else {
                if ours {
                    let failed = Marker::Failed { exit_code: status.code(), host: hostname() };
                    write_marker(&dir, cell.index, Some(&failed))?;
                }
                say(&format!(
                    "cell {} ({}): failed ({status}) after {secs:.1} s; see {}",
                    cell.index,
                    one_line(&cell.name),
                    log_path(&dir, cell.index).display()
                ));
                report.failed.push(cell.index);
            }
        }
    }
    report.finished.sort_unstable();
    report.failed.sort_unstable();
    Ok(report)
}

/// The log of cell `index`.
pub fn log_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(LOGS_DIR).join(format!("{index}.log"))
}

/// Starts `quadcl run` on `cell`, its output appended to its log.
fn spawn_cell(dir: &Path, cell: &Cell, options: &LocalOptions) -> anyhow::Result<Child> {
    let log = log_path(dir, cell.index);
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log)
        .with_context(|| format!("opening {}", log.display()))?;
    writeln!(
        file,
        "== quadcl sweep local: cell {} ({}), {} threads",
        cell.index,
        one_line(&cell.name),
        options.threads_per_job
    )
    .with_context(|| format!("writing {}", log.display()))?;
    let err = file.try_clone().with_context(|| format!("opening {}", log.display()))?;
    let mut command = Command::new(&options.quadcl);
    command
        .arg("run")
        .arg("--config")
        .arg(dir.join(&cell.config))
        .arg("--out")
        .arg(dir.join(&cell.run))
        .arg("--resume")
        .current_dir(dir)
        .env("RAYON_NUM_THREADS", options.threads_per_job.to_string())
        .stdin(Stdio::null())
        .stdout(Stdio::from(file))
        .stderr(Stdio::from(err));
    die_with_parent(&mut command);
    command.spawn().with_context(|| format!("starting {} for cell {}", options.quadcl.display(), cell.index))
}

/// Linux: the child gets SIGKILL when the sweep's thread that started it ends (the sweep
/// was killed), so no orphan goes on writing into a run folder the next sweep resumes.
#[cfg(target_os = "linux")]
fn die_with_parent(command: &mut Command) {
    use std::os::unix::process::CommandExt;
    let parent = std::process::id();
    // SAFETY: prctl, getppid and _exit are async-signal-safe and touch only the child itself.
    unsafe {
        command.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // The sweep died before the signal was armed: do not start at all.
            if libc::getppid() as u32 != parent {
                libc::_exit(1);
            }
            Ok(())
        });
    }
}

#[cfg(not(target_os = "linux"))]
fn die_with_parent(_command: &mut Command) {}

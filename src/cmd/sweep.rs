//! `quadcl sweep plan|local|slurm|status|collect|finetunes`: grids of runs (see the
//! library's `sweep` module for the folder they share).
//!
//! ```text
//! quadcl sweep plan scenes/sweep-smoke.toml --out runs/sweep-smoke
//! quadcl sweep local runs/sweep-smoke --jobs 2
//! quadcl sweep slurm runs/sweep-smoke --time 02:00:00 --cpus-per-task 4 --submit
//! quadcl sweep status runs/sweep-smoke
//! quadcl sweep collect runs/sweep-smoke
//! quadcl sweep finetunes runs/findings/sim2real
//! ```

use clap::{Args, Subcommand};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct SweepArgs {
    #[command(subcommand)]
    pub command: SweepCommand,
}

#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Expand a sweep file into one run file per cell (DIR/cells/I.toml) and DIR/sweep.json, every cell checked.
    Plan(PlanArgs),
    /// Train every cell that has not finished on this machine (resuming stopped ones), N at a time;
    /// several on one folder share its cells.
    Local(LocalArgs),
    /// Write DIR/sweep.sbatch, a Slurm array job of the unfinished cells, and submit it with --submit.
    Slurm(SlurmArgs),
    /// Where every cell stands: pending, queued, running (with progress), stopped, failed, finished.
    Status(StatusArgs),
    /// Per group of cells that differ only in seed: means with 90 % bootstrap intervals (DIR/collected.md, .json).
    Collect(CollectArgs),
    /// Sim-to-real fine-tunings over seeds (DIR/*/finetune.json, one per seed): every task on the shifted
    /// robot before and after, with intervals, and whether any other task changed (DIR/finetunes.md, .json).
    Finetunes(FinetunesArgs),
}

#[derive(Debug, Args)]
pub struct FinetunesArgs {
    /// The folder of the seeds' fine-tunings, each `quadcl finetune --out DIR/NAME`.
    pub dir: PathBuf,
}

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The sweep file (TOML): `base = "RUN_FILE"` and an [axes] table of run file keys and their values.
    pub file: PathBuf,
    /// The sweep folder to plan into.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Debug, Args)]
pub struct LocalArgs {
    /// The sweep folder (from `quadcl sweep plan`).
    pub dir: PathBuf,
    /// Cells trained at the same time.
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Worker threads per cell (default: the cores shared among the jobs).
    #[arg(long)]
    pub threads_per_job: Option<usize>,
}

#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// The sweep folder (from `quadcl sweep plan`), on a file system the nodes share.
    pub dir: PathBuf,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per cell (HH:MM:SS).
    #[arg(long)]
    pub time: Option<String>,
    /// CPUs per cell (its RAYON_NUM_THREADS).
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: usize,
    /// Memory per cell (4G, 4000M).
    #[arg(long)]
    pub mem: Option<String>,
    /// The quadcl binary the nodes run (default: this one).
    #[arg(long)]
    pub quadcl: Option<PathBuf>,
    /// Submit the script with sbatch (and record the job in DIR/slurm.json).
    #[arg(long)]
    pub submit: bool,
}

#[derive(Debug, Args)]
pub struct StatusArgs {
    /// The sweep folder.
    pub dir: PathBuf,
    /// Print the cells as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct CollectArgs {
    /// The sweep folder.
    pub dir: PathBuf,
    /// Also per task of each group: performance at the end, forgetting, falls and tracking
    /// errors over the seeds (DIR/collected-tasks.md, .json).
    #[arg(long)]
    pub per_task: bool,
    /// Also each group's plasticity (each task's performance right after its own training) step
    /// by step, its first half of the steps against the second and its slope, paired within
    /// each seed (DIR/plasticity-trend.md, .json).
    #[arg(long)]
    pub plasticity_trend: bool,
    /// Also every group minus this one, paired by seed, with intervals (DIR/contrast.md, .json):
    /// a group's name as the table prints it, or the parts that pick it out (`name=ours`).
    #[arg(long, value_name = "GROUP")]
    pub against: Option<String>,
    /// The sweep folder that holds --against's group, when it is another one run at the same
    /// seeds (DIR/contrast-vs-OTHER.md, .json).
    #[arg(long, value_name = "OTHER", requires = "against")]
    pub against_in: Option<PathBuf>,
}

pub fn run(args: SweepArgs) -> anyhow::Result<()> {
    use quadcl::sweep;
    match args.command {
        SweepCommand::Plan(a) => {
            let plan = sweep::plan(&a.file, &a.out)?;
            for c in &plan.cells {
                println!("{:>4}  {}", c.index, c.name);
            }
            println!(
                "{} cells in {} groups planned into {} (run them with `quadcl sweep local {}` or `quadcl sweep slurm {} --submit`)",
                plan.cells.len(),
                plan.groups().len(),
                a.out.display(),
                a.out.display(),
                a.out.display()
            );
            Ok(())
        }
        SweepCommand::Local(a) => {
            anyhow::ensure!(a.jobs >= 1, "--jobs = 0: expected at least 1");
            let mut options = sweep::LocalOptions::sharing_cores(a.jobs, std::env::current_exe()?);
            if let Some(t) = a.threads_per_job {
                anyhow::ensure!(t >= 1, "--threads-per-job = 0: expected at least 1");
                options.threads_per_job = t;
            }
            let report = sweep::run_local(&a.dir, &options, &mut |line| eprintln!("{line}"))?;
            anyhow::ensure!(
                report.failed.is_empty(),
                "cells {:?} failed (their logs are in {}/logs): `quadcl sweep local` again resumes them",
                report.failed,
                a.dir.display()
            );
            let elsewhere = match report.running_elsewhere.len() {
                0 => String::new(),
                n => format!(", {n} left to another process"),
            };
            println!(
                "{} cells finished now, {} before{elsewhere}; collect with `quadcl sweep collect {}`",
                report.finished.len(),
                report.already_finished.len(),
                a.dir.display()
            );
            Ok(())
        }
        SweepCommand::Slurm(a) => {
            let quadcl = match a.quadcl {
                Some(p) => std::path::absolute(p)?,
                None => std::env::current_exe()?,
            };
            let options = sweep::SlurmOptions {
                partition: a.partition,
                time: a.time,
                cpus_per_task: a.cpus_per_task,
                mem: a.mem,
                quadcl,
            };
            let (script, cells) = sweep::write_sbatch(&a.dir, &options)?;
            println!("{}: an array of {} cells", script.display(), cells.len());
            if a.submit {
                let dir = std::path::absolute(&a.dir)?;
                let job = sweep::submit(&dir, &cells)?;
                println!("submitted as job {job}; follow it with `quadcl sweep status {}`", a.dir.display());
            } else {
                println!("submit it with `sbatch {}` (or again with --submit)", script.display());
            }
            Ok(())
        }
        SweepCommand::Status(a) => {
            let cells = sweep::status(&a.dir, true)?;
            if a.json {
                println!("{}", serde_json::to_string_pretty(&cells)?);
            } else {
                print!("{}", sweep::status_lines(&cells));
            }
            Ok(())
        }
        SweepCommand::Collect(a) => {
            let table = sweep::collect(&a.dir)?;
            // A baseline no group has fails before anything is written.
            let contrast = match (&a.against, &a.against_in) {
                (Some(against), None) => Some(sweep::contrast(&table, against)?),
                (Some(against), Some(other)) => {
                    let other_table = sweep::collect(other)?;
                    let relative = relative_path(&a.dir, other)?;
                    Some(sweep::contrast::contrast_across(&table, &other_table, &relative, against)?)
                }
                _ => None,
            };
            sweep::collect::write_collected(&a.dir, &table)?;
            print!("{}", sweep::markdown(&table));
            say_written(&a.dir, sweep::COLLECTED_MD, sweep::COLLECTED_JSON);
            if a.per_task {
                let tasks = sweep::collect_tasks_and_write(&a.dir)?;
                print!("\n{}", sweep::tasks_markdown(&tasks));
                say_written(&a.dir, sweep::per_task::COLLECTED_TASKS_MD, sweep::per_task::COLLECTED_TASKS_JSON);
            }
            if a.plasticity_trend {
                let trend = sweep::plasticity_trend_and_write(&a.dir)?;
                print!("\n{}", sweep::trend_markdown(&trend));
                say_written(
                    &a.dir,
                    sweep::plasticity_trend::PLASTICITY_TREND_MD,
                    sweep::plasticity_trend::PLASTICITY_TREND_JSON,
                );
            }
            if let Some(c) = contrast {
                let (md, json) = sweep::contrast::write_contrast(&a.dir, &c)?;
                print!("\n{}", sweep::contrast_markdown(&c));
                println!("\nwritten to {} and {}", md.display(), json.display());
            }
            Ok(())
        }
        SweepCommand::Finetunes(a) => {
            let table = sweep::finetunes_and_write(&a.dir)?;
            print!("{}", sweep::finetunes_markdown(&table));
            say_written(&a.dir, sweep::finetunes::FINETUNES_MD, sweep::finetunes::FINETUNES_JSON);
            let figure = a.dir.join(FINETUNES_PNG);
            quadcl::util::write_atomic(&figure, &quadcl::plot::finetunes_png(&table)?)?;
            println!("figure: {}", figure.display());
            Ok(())
        }
    }
}

/// `quadcl sweep finetunes`'s figure beside its tables: every task before and after, per seed.
const FINETUNES_PNG: &str = "finetunes.png";

/// The line after a printed table: the two files in `dir` it was written to.
fn say_written(dir: &std::path::Path, md: &str, json: &str) {
    println!("\nwritten to {} and {}", dir.join(md).display(), dir.join(json).display());
}

/// `to` relative to the folder `from` (both must exist), as `../fig5-selection`.
fn relative_path(from: &std::path::Path, to: &std::path::Path) -> anyhow::Result<String> {
    use anyhow::Context;
    let canon = |p: &std::path::Path| p.canonicalize().with_context(|| format!("{}: no such folder", p.display()));
    let (from, to) = (canon(from)?, canon(to)?);
    let common = from.components().zip(to.components()).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = from.components().skip(common).map(|_| "..".to_string()).collect();
    parts.extend(to.components().skip(common).map(|c| c.as_os_str().to_string_lossy().into_owned()));
    Ok(if parts.is_empty() { ".".into() } else { parts.join("/") })
}

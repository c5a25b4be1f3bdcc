//! A sweep as a Slurm array job (`quadcl sweep slurm DIR [--submit]`):
//! `DIR/sweep.sbatch` is an array whose task I runs
//! `quadcl run --config cells/I.toml --out runs/I --resume` in the sweep folder
//! (so a preempted or requeued task continues where it stopped), with its
//! output in `logs/I.log` (the same log `sweep local` writes, so status and
//! progress read the same) and `RAYON_NUM_THREADS` set to the task's CPUs. The
//! array holds only the cells that have not finished. `--submit` hands it to
//! `sbatch` and records the job in `DIR/slurm.json`; `sweep status` then asks
//! `squeue` (queued, running) and `sacct` (failed, when accounting is on).

use super::plan::Plan;
use super::status::cell_finished;
use super::{LOGS_DIR, SBATCH_FILE, SLURM_FILE};
use crate::util::write_atomic;
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The resources each array task asks for.
#[derive(Debug, Clone, Default)]
pub struct SlurmOptions {
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` (`HH:MM:SS`, `MM:SS` or `D-HH:MM:SS`).
    pub time: Option<String>,
    /// `--cpus-per-task` (also the task's `RAYON_NUM_THREADS`).
    pub cpus_per_task: usize,
    /// `--mem` (`4G`, `4000M`, `4000`).
    pub mem: Option<String>,
    /// The quadcl binary the tasks run (on a cluster: a path every node sees).
    pub quadcl: PathBuf,
}

/// A submitted array job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SubmittedJob {
    pub job_id: String,
    /// The cells its array holds.
    pub cells: Vec<usize>,
}

/// `slurm.json`: the array jobs submitted for the sweep, oldest first.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SlurmJobs {
    pub jobs: Vec<SubmittedJob>,
}

impl SlurmJobs {
    /// The jobs recorded in `dir` (none when nothing was submitted).
    pub fn load(dir: &Path) -> anyhow::Result<Self> {
        let path = dir.join(SLURM_FILE);
        if !path.exists() {
            return Ok(Self::default());
        }
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{}: not a record of Slurm jobs", path.display()))
    }
}

/// Checks an option's value before it goes into the script: `what` names the option.
fn check_option(what: &str, value: &str, ok: impl Fn(char) -> bool) -> anyhow::Result<()> {
    anyhow::ensure!(
        !value.is_empty() && value.chars().all(ok),
        "{what} {value:?}: unexpected characters (see `man sbatch` for the form)"
    );
    Ok(())
}

/// `'text'` for a POSIX shell.
fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// `path` as the inside of a double-quoted word of an `#SBATCH` line's file name pattern.
/// sbatch's directive reader (`_get_argument`) ends a word at white space unless it is inside
/// quotes (a backslash does not protect a space), takes a backslash as escaping the next
/// character (so a `"` inside the quotes is written `\"`) and ends the line at an unquoted
/// `#`; `%` (the pattern's own escape) is doubled. A backslash or a control character in the
/// path is refused: after the reader a backslash would turn the pattern's `%a` off.
fn sbatch_quoted_pattern(path: &str) -> anyhow::Result<String> {
    anyhow::ensure!(
        !path.chars().any(|c| c == '\\' || c.is_control()),
        "the folder {:?} holds a backslash or a control character, which an #SBATCH line cannot carry: \
         plan the sweep into a folder whose path has neither",
        crate::util::text::clip(path)
    );
    Ok(path.replace('%', "%%").replace('"', "\\\""))
}

/// `0-3,5,7-8`: the indices as Slurm's array ranges.
pub fn array_ranges(cells: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < cells.len() {
        let mut j = i;
        while j + 1 < cells.len() && cells[j + 1] == cells[j] + 1 {
            j += 1;
        }
        parts.push(if i == j { cells[i].to_string() } else { format!("{}-{}", cells[i], cells[j]) });
        i = j + 1;
    }
    parts.join(",")
}

/// The array job script for `cells` of the sweep folder `dir` (absolute).
pub fn sbatch_script(dir: &Path, cells: &[usize], options: &SlurmOptions) -> anyhow::Result<String> {
    if let Some(p) = &options.partition {
        check_option("--partition", p, |c| c.is_ascii_alphanumeric() || "_-,.".contains(c))?;
    }
    if let Some(t) = &options.time {
        check_option("--time", t, |c| c.is_ascii_digit() || c == ':' || c == '-')?;
    }
    if let Some(m) = &options.mem {
        check_option("--mem", m, |c| c.is_ascii_digit() || "KMGTkmgt".contains(c))?;
    }
    anyhow::ensure!(options.cpus_per_task >= 1, "--cpus-per-task = 0: expected at least 1");
    anyhow::ensure!(!cells.is_empty(), "{}: every cell has finished, nothing to submit", dir.display());
    let shown = dir.display().to_string();
    let logs = sbatch_quoted_pattern(&format!("{shown}/{LOGS_DIR}/"))?;
    let mut s = String::from("#!/bin/bash\n");
    s.push_str(&format!(
        "# The sweep {} as a Slurm array job, written by `quadcl sweep slurm`: task I trains cell I\n\
         # (cells/I.toml into runs/I), resuming it where it stopped (a preempted or requeued task continues).\n",
        crate::util::text::one_line(&shown)
    ));
    s.push_str("#SBATCH --job-name=quadcl-sweep\n");
    s.push_str(&format!("#SBATCH --array={}\n", array_ranges(cells)));
    s.push_str(&format!("#SBATCH --cpus-per-task={}\n", options.cpus_per_task));
    s.push_str("#SBATCH --ntasks=1\n");
    s.push_str(&format!("#SBATCH --output=\"{logs}%a.log\"\n"));
    s.push_str("#SBATCH --open-mode=append\n#SBATCH --requeue\n");
    for (flag, value) in [("partition", &options.partition), ("time", &options.time), ("mem", &options.mem)] {
        if let Some(v) = value {
            s.push_str(&format!("#SBATCH --{flag}={v}\n"));
        }
    }
    s.push_str("set -euo pipefail\n");
    s.push_str(&format!("export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-{}}}\"\n", options.cpus_per_task));
    s.push_str(&format!("cd {}\n", shell_quote(&shown)));
    s.push_str(&format!(
        "exec {} run --config \"cells/${{SLURM_ARRAY_TASK_ID}}.toml\" --out \"runs/${{SLURM_ARRAY_TASK_ID}}\" --resume\n",
        shell_quote(&options.quadcl.display().to_string())
    ));
    Ok(s)
}

/// Writes `DIR/sweep.sbatch` for the cells of the sweep in `dir` that have not finished;
/// returns its path and those cells.
pub fn write_sbatch(dir: &Path, options: &SlurmOptions) -> anyhow::Result<(PathBuf, Vec<usize>)> {
    let dir = std::path::absolute(dir).with_context(|| format!("{}: no absolute path", dir.display()))?;
    let plan = Plan::load(&dir)?;
    plan.check_cells(&dir)?;
    let cells: Vec<usize> = plan.cells.iter().filter(|c| !cell_finished(&dir, c)).map(|c| c.index).collect();
    let script = sbatch_script(&dir, &cells, options)?;
    std::fs::create_dir_all(dir.join(LOGS_DIR))
        .with_context(|| format!("creating {}", dir.join(LOGS_DIR).display()))?;
    let path = dir.join(SBATCH_FILE);
    write_atomic(&path, script.as_bytes())?;
    Ok((path, cells))
}

/// Submits `DIR/sweep.sbatch` (holding `cells`) with `sbatch` and records the job in `slurm.json`.
pub fn submit(dir: &Path, cells: &[usize]) -> anyhow::Result<String> {
    let script = dir.join(SBATCH_FILE);
    let out = Command::new("sbatch").arg("--parsable").arg(&script).output().context(
        "running sbatch (is Slurm installed here? `quadcl sweep slurm` without --submit only writes the script)",
    )?;
    anyhow::ensure!(
        out.status.success(),
        "sbatch {} failed ({}): {}",
        script.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr).trim()
    );
    // --parsable prints `JOBID` or `JOBID;CLUSTER`.
    let stdout = String::from_utf8_lossy(&out.stdout);
    let job_id = stdout.trim().split(';').next().unwrap_or_default().to_string();
    anyhow::ensure!(
        !job_id.is_empty() && job_id.chars().all(|c| c.is_ascii_digit()),
        "sbatch printed {stdout:?}, not a job id"
    );
    let mut jobs = SlurmJobs::load(dir)?;
    jobs.jobs.push(SubmittedJob { job_id: job_id.clone(), cells: cells.to_vec() });
    write_atomic(&dir.join(SLURM_FILE), serde_json::to_string_pretty(&jobs)?.as_bytes())?;
    Ok(job_id)
}

/// Per cell, its array task's state from `program` (`squeue` or `sacct`) for the newest
/// recorded job holding it; None when nothing was submitted or the program is missing or fails.
pub fn task_states(dir: &Path, program: &str) -> Option<BTreeMap<usize, String>> {
    let jobs = SlurmJobs::load(dir).ok()?;
    if jobs.jobs.is_empty() {
        return None;
    }
    let mut states = BTreeMap::new();
    for job in &jobs.jobs {
        let output = match program {
            "squeue" => Command::new("squeue").args(["-h", "-r", "-j", &job.job_id, "-o", "%i|%T"]).output(),
            _ => Command::new("sacct").args(["-n", "-P", "-X", "-j", &job.job_id, "-o", "JobID,State"]).output(),
        };
        let output = output.ok().filter(|o| o.status.success())?;
        let parsed = parse_task_states(&String::from_utf8_lossy(&output.stdout), &job.job_id);
        // A later job's state replaces an earlier one's for the same cell.
        states.extend(parsed.into_iter().filter(|(cell, _)| job.cells.contains(cell)));
    }
    Some(states)
}

/// `JOB_I|STATE` lines (squeue `-r -o "%i|%T"`, sacct `-P -o JobID,State`) of job `job_id`:
/// per array index, its state's first word (`CANCELLED by 0` -> `CANCELLED`).
pub fn parse_task_states(text: &str, job_id: &str) -> BTreeMap<usize, String> {
    let mut states = BTreeMap::new();
    for line in text.lines() {
        let Some((id, state)) = line.trim().split_once('|') else { continue };
        let Some(index) = id.strip_prefix(job_id).and_then(|r| r.strip_prefix('_')) else { continue };
        if let (Ok(index), Some(state)) = (index.parse::<usize>(), state.split_whitespace().next()) {
            states.insert(index, state.to_string());
        }
    }
    states
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_array_lists_the_unfinished_cells_as_ranges() {
        assert_eq!(array_ranges(&[0, 1, 2, 3]), "0-3");
        assert_eq!(array_ranges(&[0, 2, 3, 5, 7, 8, 9]), "0,2-3,5,7-9");
        assert_eq!(array_ranges(&[4]), "4");
    }

    #[test]
    fn the_script_runs_each_cell_resumable_with_the_options_asked_for() {
        let options = SlurmOptions {
            partition: Some("cpu".into()),
            time: Some("02:00:00".into()),
            cpus_per_task: 4,
            mem: Some("8G".into()),
            quadcl: "/opt/quadcl it's/quadcl".into(),
        };
        let s = sbatch_script(Path::new("/scratch/sweep"), &[0, 1, 3], &options).unwrap();
        for line in [
            "#SBATCH --array=0-1,3",
            "#SBATCH --cpus-per-task=4",
            "#SBATCH --partition=cpu",
            "#SBATCH --time=02:00:00",
            "#SBATCH --mem=8G",
            "#SBATCH --output=\"/scratch/sweep/logs/%a.log\"",
            "export RAYON_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-4}\"",
            "exec '/opt/quadcl it'\\''s/quadcl' run --config \"cells/${SLURM_ARRAY_TASK_ID}.toml\" --out \"runs/${SLURM_ARRAY_TASK_ID}\" --resume",
        ] {
            assert!(s.lines().any(|l| l == line), "no line {line:?} in\n{s}");
        }
        let bad = SlurmOptions { time: Some("2h; rm -rf /".into()), ..options.clone() };
        let err = format!("{:#}", sbatch_script(Path::new("/s"), &[0], &bad).unwrap_err());
        assert!(err.contains("--time"), "{err}");
        assert!(sbatch_script(Path::new("/s"), &[], &options).is_err());
    }

    /// The argument sbatch's directive reader takes from `line`, as its `_get_argument` reads it:
    /// a word ends at white space outside quotes (checked before any escape), quotes group, a
    /// backslash escapes the next character, an unquoted `#` ends the line.
    fn sbatch_reads(line: &str) -> String {
        let (mut out, mut quote, mut escaped) = (String::new(), None, false);
        for c in line.chars() {
            if quote.is_none() && c.is_whitespace() {
                break;
            }
            if escaped {
                escaped = false;
            } else if c == '\\' {
                escaped = true;
                continue;
            } else if let Some(q) = quote {
                if c == q {
                    quote = None;
                    continue;
                }
            } else if c == '"' || c == '\'' {
                quote = Some(c);
                continue;
            } else if c == '#' {
                break;
            }
            out.push(c);
        }
        out
    }

    #[test]
    fn an_odd_sweep_folder_reaches_sbatch_as_one_file_pattern() {
        let options = SlurmOptions { cpus_per_task: 1, quadcl: "/q".into(), ..SlurmOptions::default() };
        for folder in ["/scratch/my sweep's dir", "/s/a\"b#c 100%"] {
            let s = sbatch_script(Path::new(folder), &[0], &options).unwrap();
            let line = s.lines().find(|l| l.starts_with("#SBATCH --output=")).unwrap();
            let pattern = sbatch_reads(line.trim_start_matches("#SBATCH "));
            // Slurm's pattern then turns `%%` into `%` and `%a` into the array index.
            let file = pattern.replace("%a", "7").replace("%%", "%");
            assert_eq!(file, format!("--output={folder}/logs/7.log"), "{line}");
            assert!(s.contains(&format!("cd {}\n", shell_quote(folder))));
        }
        for bad in ["/s/back\\slash", "/s/line\nbreak", "/s/tab\tx"] {
            let err = format!("{:#}", sbatch_script(Path::new(bad), &[0], &options).unwrap_err());
            assert!(err.contains("#SBATCH") && !err.contains('\n'), "{err}");
        }
    }

    #[test]
    fn queue_lines_give_each_array_task_its_state() {
        let squeue = "17_0|RUNNING\n17_1|PENDING\n18_0|RUNNING\n17_[2-3]|PENDING\n";
        let states = parse_task_states(squeue, "17");
        assert_eq!(states, BTreeMap::from([(0, "RUNNING".to_string()), (1, "PENDING".to_string())]));
        let sacct = "17_2|CANCELLED by 0\n17_3|FAILED\n";
        assert_eq!(parse_task_states(sacct, "17")[&2], "CANCELLED");
    }
}

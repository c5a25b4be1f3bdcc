//! A policy that runs in another program (`quadcl eval --policy-cmd CMD`): an
//! exported model in ONNX Runtime or NumPy (`scripts/policy_server.py`), or a
//! controller written in any language, driving quadcl's simulator.
//!
//! The program is started with `sh -c CMD` and the variables QUADCL_NUM_ENVS,
//! QUADCL_OBS_DIM, QUADCL_HISTORY_LEN and QUADCL_ACT_DIM. At every control step
//! quadcl writes every environment's observation history to its standard input,
//! (N, H * obs) little-endian f32, oldest frame first (the last frame is the
//! current observation), and reads (N, act) little-endian f32 actions from its
//! standard output. Closing its input asks it to exit. Its standard error is the
//! terminal's.

use super::env::EnvDims;
use anyhow::Context;
use std::io::{BufReader, Read, Write};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

/// A running policy program.
#[derive(Debug)]
pub struct ExternalPolicy {
    command: String,
    child: Child,
    input: Option<ChildStdin>,
    output: BufReader<ChildStdout>,
    dims: EnvDims,
    num_envs: usize,
}

impl ExternalPolicy {
    /// Starts `command` for `num_envs` environments of `dims`.
    pub fn spawn(command: &str, dims: EnvDims, num_envs: usize) -> anyhow::Result<Self> {
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(command)
            .env("QUADCL_NUM_ENVS", num_envs.to_string())
            .env("QUADCL_OBS_DIM", dims.obs.to_string())
            .env("QUADCL_HISTORY_LEN", dims.history_len.to_string())
            .env("QUADCL_ACT_DIM", dims.act.to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .with_context(|| format!("starting the policy command `{command}`"))?;
        let input = child.stdin.take().context("the policy command has no standard input")?;
        let output = BufReader::new(child.stdout.take().context("the policy command has no standard output")?);
        Ok(Self { command: command.to_string(), child, input: Some(input), output, dims, num_envs })
    }

    /// What the program said when it stopped answering: its exit status if it has one.
    fn stopped(&mut self, what: &str, e: std::io::Error) -> anyhow::Error {
        let status = match self.child.try_wait() {
            Ok(Some(s)) => format!("it exited with {s}"),
            _ => "it is still running".to_string(),
        };
        anyhow::anyhow!("policy command `{}`: {what}: {e} ({status}; its messages are above)", self.command)
    }

    /// Actions (N, act) for observation histories (N, H * obs).
    pub fn act(&mut self, histories: &[f32]) -> anyhow::Result<Vec<f32>> {
        let width = self.dims.history_len * self.dims.obs;
        anyhow::ensure!(
            histories.len() == self.num_envs * width,
            "{} history values for {} envs",
            histories.len(),
            self.num_envs
        );
        let bytes: Vec<u8> = histories.iter().flat_map(|v| v.to_le_bytes()).collect();
        let input = self.input.as_mut().context("the policy command's input is closed")?;
        if let Err(e) = input.write_all(&bytes).and_then(|()| input.flush()) {
            return Err(self.stopped("writing observations", e));
        }
        let mut answer = vec![0u8; self.num_envs * self.dims.act * 4];
        if let Err(e) = self.output.read_exact(&mut answer) {
            return Err(self.stopped(&format!("reading {} actions", self.num_envs * self.dims.act), e));
        }
        Ok(answer.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
    }

    /// Closes the program's input and waits for it; a failing exit is an error.
    pub fn finish(mut self) -> anyhow::Result<()> {
        drop(self.input.take());
        let status = self.child.wait().with_context(|| format!("waiting for `{}`", self.command))?;
        anyhow::ensure!(status.success(), "policy command `{}` exited with {status}", self.command);
        Ok(())
    }
}

impl Drop for ExternalPolicy {
    fn drop(&mut self) {
        drop(self.input.take());
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

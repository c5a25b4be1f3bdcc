//! `quadcl._native`: the Rust side of quadcl's Python package (`python/quadcl/`
//! wraps it in Gymnasium's vector API). Every call that does work runs with the
//! GIL released; arrays cross as NumPy arrays, one per batch, never one Python
//! object per environment.
//!
//! | file | what |
//! | --- | --- |
//! | `settings` | a robot's `[env]` settings by name, URDF or config file; a run file's sequence |
//! | `vec_env` | `NativeVecEnv`: the learner's batch of environments, stepped in one call |
//! | `policy` | `NativePolicy` (a learned task's deterministic policy) and `evaluate` |
//!
//! Errors: a quadcl error becomes a `ValueError` (bad input: settings, names,
//! shapes) or an `OSError` (a file), its message the whole chain; a Rust panic
//! inside a call becomes a `RuntimeError` instead of aborting the interpreter.

mod policy;
mod settings;
mod vec_env;

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Runs `f`, turning its error into a Python exception and a panic into `RuntimeError`.
pub(crate) fn guard<T>(what: &str, f: impl FnOnce() -> anyhow::Result<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(to_py_err(&e)),
        Err(payload) => {
            let message = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "no message".into());
            Err(PyRuntimeError::new_err(format!("quadcl panicked in {what}: {message}")))
        }
    }
}

/// A file that cannot be read is an `OSError`; every other error a `ValueError`.
pub(crate) fn to_py_err(e: &anyhow::Error) -> PyErr {
    let message = quadcl::util::text::error_text(e);
    if e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some()) {
        PyOSError::new_err(message)
    } else {
        PyValueError::new_err(message)
    }
}

/// Panics inside a guarded call: the tests check that a panic becomes a `RuntimeError`.
#[pyfunction]
fn _panic_for_test(message: String) -> PyResult<()> {
    guard("_panic_for_test", || -> anyhow::Result<()> { panic!("{message}") })
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<vec_env::NativeVecEnv>()?;
    m.add_class::<policy::NativePolicy>()?;
    m.add_function(wrap_pyfunction!(settings::env_settings, m)?)?;
    m.add_function(wrap_pyfunction!(settings::sequence_of, m)?)?;
    m.add_function(wrap_pyfunction!(settings::task_name, m)?)?;
    m.add_function(wrap_pyfunction!(policy::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_test, m)?)?;
    m.add("OBS_DIM", quadcl::sim::OBS_DIM)?;
    m.add("HISTORY_LEN", quadcl::sim::HISTORY_LEN)?;
    m.add("ACT_DIM", quadcl::sim::ACT_DIM)?;
    m.add("PRIV_OBS_DIM", quadcl::sim::PRIV_OBS_DIM)?;
    m.add("SHIPPED_ROBOTS", quadcl::engine::SHIPPED_ROBOTS.iter().map(|(n, _)| *n).collect::<Vec<_>>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

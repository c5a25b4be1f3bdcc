//! Environment throughput (owned by the `sim` work; skeleton).

/// Adds the environment figures to `report`.
pub fn measure(_seconds: f64, _report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    Ok(())
}

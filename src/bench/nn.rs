//! Masked network throughput (owned by the `nn` work; skeleton).

/// Adds the network figures to `report`.
pub fn measure(_seconds: f64, _report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    Ok(())
}

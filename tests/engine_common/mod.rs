//! Checks shared by the engine's integration tests.

use std::path::Path;

/// Reads `out/metrics.json` and asserts it has every top-level field a run writes.
pub fn assert_metrics_json_complete(out: &Path) -> serde_json::Value {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    for key in [
        "method",
        "tasks",
        "eval_matrix",
        "average_performance",
        "forgetting",
        "forward_transfer",
        "plasticity",
        "curves",
        "command_tracking",
        "steps",
        "evaluations",
    ] {
        assert!(json.get(key).is_some(), "metrics.json has no {key}");
    }
    json
}

//! `quadcl bench --only accuracy`: the simulator's exactness at the default step and at
//! MuJoCo's reference step, printed by a fixed number of steps (so the figures repeat).

use std::process::Command;

fn accuracy() -> serde_json::Map<String, serde_json::Value> {
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["bench", "--json", "--only", "accuracy"])
        .output()
        .expect("quadcl runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    match serde_json::from_slice(&out.stdout).expect("bench prints JSON") {
        serde_json::Value::Object(map) => map,
        other => panic!("not an object: {other}"),
    }
}

fn figure(report: &serde_json::Map<String, serde_json::Value>, key: &str) -> f64 {
    report.get(key).and_then(|v| v.as_f64()).unwrap_or_else(|| panic!("{key} missing from {report:?}"))
}

#[test]
fn the_accuracy_figures_repeat_and_the_finer_step_is_more_exact_under_violent_actions() {
    let first = accuracy();
    assert_eq!(first, accuracy(), "the same binary printed different accuracy figures");
    for step in ["dt001x2", "dt0005x4"] {
        for scenario in ["stand", "trot"] {
            let height = figure(&first, &format!("accuracy_{scenario}_trunk_height_m_{step}"));
            assert!((0.2..0.4).contains(&height), "{scenario} at {step}: trunk at {height} m");
            let err = figure(&first, &format!("accuracy_{scenario}_joint_err_rad_{step}"));
            assert!(err > 0.0 && err < 0.3, "{scenario} at {step}: joint error {err} rad");
        }
    }
    // Standing, the two steps agree closely; under violent actions the smaller step lets feet
    // sink less and joints overshoot their limits less.
    let stand_gap = figure(&first, "accuracy_stand_trunk_height_m_dt001x2")
        - figure(&first, "accuracy_stand_trunk_height_m_dt0005x4");
    assert!(stand_gap.abs() < 0.01, "standing heights differ by {stand_gap} m");
    assert!(
        figure(&first, "accuracy_violent_foot_sink_m_dt0005x4")
            < figure(&first, "accuracy_violent_foot_sink_m_dt001x2")
    );
    assert!(
        figure(&first, "accuracy_violent_limit_overshoot_rad_dt0005x4")
            < figure(&first, "accuracy_violent_limit_overshoot_rad_dt001x2")
    );
}

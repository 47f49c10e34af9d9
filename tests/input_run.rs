//! End to end: `mocu run` headless with a scripted gamepad (`--input-script`) drives the
//! simulated `usv1`; the refused call shows in the toast list on screen and in the log.

use std::process::Command;

#[test]
fn a_scripted_gamepad_drives_usv1_in_a_headless_run_with_feedback_on_screen_and_in_the_log() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("trial.jsonl");
    let shot = dir.path().join("shot.png");
    let out = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args([
            "run",
            "tests/input/drive.mocu",
            "--headless",
            "--frames",
            "90",
            "--size",
            "640x400",
        ])
        .args(["--mavlink", "off", "--video", "off", "--no-watch"])
        .args(["--input-script", "tests/input/drive.script"])
        .arg("--log")
        .arg(&log)
        .arg("--screenshot")
        .arg(&shot)
        .args(["--dump", "root"])
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("module input (input) started"), "{stderr}");
    assert!(stderr.contains("gamepad connected: Scripted Pad"), "{stderr}");
    let dump: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let nav = find(&dump, &["vehicles", "usv1", "nav"]).expect("usv1.nav in the dump");
    // The stick's last position: 0.9 through deadzone 0.1 and expo 0.3, ×100.
    let x: f64 = 8.0 / 9.0;
    let thr = 100.0 * (0.7 * x + 0.3 * x.powi(3));
    let got = nav["properties"]["goal_throttle"].as_f64().unwrap();
    assert!((got - thr).abs() < 1e-9, "goal_throttle {got}, want {thr}");
    let rud = nav["properties"]["goal_rudder"].as_f64().unwrap();
    assert!((rud + 30.0 * 0.45 / 0.95).abs() < 1e-9, "goal_rudder {rud}");
    let toasts = find(&dump, &["operator", "toasts"]).expect("the toast list");
    assert_eq!(
        toasts["properties"]["t1"], "usv1.start_engine: refused — engine already running",
        "the refused call is the newest toast"
    );
    let log = std::fs::read_to_string(&log).unwrap();
    assert!(log.contains(r#""event":"input""#) && log.contains("Scripted Pad"), "{log}");
    assert!(
        log.contains(r#""kind":"set","target":"root.vehicles.usv1.nav.goal_throttle""#),
        "{log}"
    );
    assert!(
        log.contains(r#""outcome":"refused","reason":"engine already running","target":"root.vehicles.usv1.start_engine""#),
        "{log}"
    );
    assert!(
        log.contains(r#""outcome":"accepted","reason":"","target":"root.vehicles.usv1.set_mode""#)
    );
    assert!(std::fs::metadata(&shot).unwrap().len() > 1000, "a screenshot");
}

/// The object at a path of names below the dumped root.
fn find<'a>(mut o: &'a serde_json::Value, names: &[&str]) -> Option<&'a serde_json::Value> {
    for n in names {
        o = o["children"].as_array()?.iter().find(|c| c["name"] == *n)?;
    }
    Some(o)
}

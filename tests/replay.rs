//! `mocu replay` on the shipped trial (tests/data/trial.mcap, a few seconds of the simulator
//! driven by a scripted gamepad through tests/replay/trial.mocu): deterministic frames,
//! golden frames with `--expect`, and a changed display caught with a diff image.
//!
//! After a deliberate change to what the display draws, refresh the golden with
//! `mocu replay tests/data/trial.mcap --at 2.5s --screenshot tests/data/trial-2.5s.png`.

mod cli_support;
use cli_support::sky_share;
use std::path::Path;
use std::process::{Command, Output};

fn replay(args: &[&str], extra: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mocu"))
        .arg("replay")
        .arg("tests/data/trial.mcap")
        .args(args)
        .args(extra)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("DISPLAY")
        .output()
        .expect("mocu runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn replaying_the_same_trial_twice_gives_the_same_png_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    for shot in [&a, &b] {
        let o = replay(&["--at", "1.7s", "--screenshot"], &[shot]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(a == b, "two replays of one trial drew different frames");
}

#[test]
fn the_frame_at_a_trial_time_matches_its_golden() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let o = replay(
        &["--at", "2.5s", "--expect", "tests/data/trial-2.5s.png", "--screenshot"],
        &[&shot],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!dir.path().join("shot.diff.png").exists());
}

#[test]
fn a_changed_layout_fails_the_golden_with_exit_1_and_a_diff_image_of_the_change() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let o = replay(
        &[
            "--at",
            "2.5s",
            "--layout",
            "tests/replay/changed.mocu",
            "--expect",
            "tests/data/trial-2.5s.png",
            "--screenshot",
        ],
        &[&shot],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("differs from tests/data/trial-2.5s.png"), "{}", stderr(&o));
    let diff = tiny_skia::Pixmap::load_png(dir.path().join("shot.diff.png")).expect("a diff image");
    // The changed label ("SPD" → "SPEED", third line, top left) is where the differences are.
    let magenta: Vec<(u32, u32)> = diff
        .pixels()
        .iter()
        .enumerate()
        .filter(|(_, p)| (p.red(), p.green(), p.blue()) == (255, 0, 255))
        .map(|(i, _)| (i as u32 % diff.width(), i as u32 / diff.width()))
        .collect();
    assert!(!magenta.is_empty());
    assert!(magenta.iter().all(|&(x, y)| x < 240 && (60..=90).contains(&y)), "{magenta:?}");
    // Within a tolerance no label change passes: the glyphs differ completely.
    let o = replay(
        &["--at", "2.5s", "--layout", "tests/replay/changed.mocu", "--tolerance", "64"],
        &[
            Path::new("--expect"),
            Path::new("tests/data/trial-2.5s.png"),
            Path::new("--screenshot"),
            &shot,
        ],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

#[test]
fn a_replay_dumps_the_world_it_replayed() {
    let o = replay(&["--at", "2.5s", "--dump", "root.vehicles"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the dump is JSON");
    let names: Vec<&str> =
        v["children"].as_array().unwrap().iter().filter_map(|c| c["name"].as_str()).collect();
    assert_eq!(names, ["usv1", "ugv1", "uav1", "usv2"]);
}

#[test]
fn a_file_that_is_not_a_recording_is_a_usage_error() {
    let o = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["replay", "tests/replay/trial.mocu", "--headless"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn a_simulator_cameras_video_is_recorded_and_shown_again_in_the_replayed_video_window() {
    let dir = tempfile::tempdir().unwrap();
    let trial = dir.path().join("usv.mcap");
    // layouts/usv.mocu shows usv1's drive camera full screen (sky above the horizon).
    let o = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["run", "layouts/usv.mocu", "--headless", "--frames", "60", "--size", "640x400"])
        .args(["--mavlink", "off", "--video", "off", "--no-watch", "--record"])
        .arg(&trial)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("mocu runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let shot = |layout: Option<&str>, name: &str| {
        let png = dir.path().join(name);
        let mut c = Command::new(env!("CARGO_BIN_EXE_mocu"));
        c.arg("replay").arg(&trial).args(["--at", "0.8s", "--screenshot"]).arg(&png);
        if let Some(l) = layout {
            c.args(["--layout", l]);
        }
        let o = c.current_dir(env!("CARGO_MANIFEST_DIR")).env_remove("DISPLAY").output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        png
    };
    // The upper right of the screen, clear of the HUD: the camera's sky in the recorded
    // layout; the map's dark sea through a layout without the video window.
    let region = ((490, 630), (60, 200));
    let video = sky_share(&shot(None, "video.png"), region.0, region.1);
    let map = sky_share(&shot(Some("tests/replay/trial.mocu"), "map.png"), region.0, region.1);
    assert!(video > 0.9, "the replayed video window shows the camera's sky ({video})");
    assert!(map < 0.1, "without a video window the sky is not there ({map})");
}

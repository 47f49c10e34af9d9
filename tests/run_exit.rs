//! How `mocu run` ends, end to end with the built binary: SIGTERM and SIGINT end a run that
//! has no `--frames`, after it wrote `--screenshot`, `--log` and `--dump`; `--dump
//! root.display` shows the display as it was at exit (the layout's windows still there).

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// Long enough for a loaded machine to start and stop fig3; a run that ignores the signal
/// never ends.
const HANG: Duration = Duration::from_secs(120);

struct Outputs {
    _dir: tempfile::TempDir,
    log: std::path::PathBuf,
    shot: std::path::PathBuf,
}

fn mocu_run(extra: &[&str]) -> (Child, Outputs) {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("trial.jsonl");
    let shot = dir.path().join("shot.png");
    let child = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["run", "layouts/fig3-multi-usv.mocu", "--headless", "--size", "640x360"])
        .args(["--mavlink", "off", "--video", "off", "--no-watch"])
        .args(["--dump", "root.display"])
        .arg("--log")
        .arg(&log)
        .arg("--screenshot")
        .arg(&shot)
        .args(extra)
        .env_remove("DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    (child, Outputs { _dir: dir, log, shot })
}

/// Reads stderr on a thread: each line goes to the channel.
fn lines(child: &mut Child) -> crossbeam_channel::Receiver<String> {
    let (tx, rx) = crossbeam_channel::unbounded();
    let err = child.stderr.take().unwrap();
    std::thread::spawn(move || {
        for l in BufReader::new(err).lines().map_while(Result::ok) {
            let _ = tx.send(l);
        }
    });
    rx
}

/// Waits (bounded) for the run to end; returns its exit status, stdout and stderr.
fn finish(
    mut child: Child,
    err: &crossbeam_channel::Receiver<String>,
    mut seen: Vec<String>,
) -> (std::process::ExitStatus, String, String) {
    let mut out = child.stdout.take().unwrap();
    let (tx, rx) = crossbeam_channel::bounded(1);
    std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut out, &mut s);
        let _ = tx.send(s);
    });
    let stdout = rx.recv_timeout(HANG);
    let status = match stdout {
        Ok(_) => child.wait().unwrap(),
        Err(_) => {
            let _ = child.kill();
            seen.extend(err.try_iter());
            panic!("mocu run did not end:\n{}", seen.join("\n"));
        }
    };
    seen.extend(err.iter());
    (status, stdout.unwrap(), seen.join("\n"))
}

/// Waits for the line that says the run is under way (signals are caught from then on).
fn wait_running(err: &crossbeam_channel::Receiver<String>) -> Vec<String> {
    let mut seen = Vec::new();
    loop {
        match err.recv_timeout(HANG) {
            Ok(l) => {
                let running = l.starts_with("mocu: running");
                seen.push(l);
                if running {
                    return seen;
                }
            }
            Err(_) => panic!("mocu run did not start:\n{}", seen.join("\n")),
        }
    }
}

fn windows_in(dump: &serde_json::Value) -> Vec<String> {
    dump["children"]
        .as_array()
        .map(|c| c.iter().filter_map(|w| w["name"].as_str().map(str::to_string)).collect())
        .unwrap_or_default()
}

#[test]
fn sigterm_sigint_and_sighup_end_a_run_after_it_wrote_the_dump_the_log_and_the_screenshot() {
    for signal in ["TERM", "INT", "HUP"] {
        let (mut child, files) = mocu_run(&[]);
        let err = lines(&mut child);
        let seen = wait_running(&err);
        let kill = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let (status, stdout, stderr) = finish(child, &err, seen);
        assert!(status.success(), "SIG{signal}: {status}\n{stderr}");
        assert!(stderr.contains(&format!("mocu: SIG{signal}: stopping")), "{stderr}");
        let dump: serde_json::Value = serde_json::from_str(&stdout)
            .unwrap_or_else(|e| panic!("SIG{signal}: the dump ({e}): {stdout}\n{stderr}"));
        assert_eq!(dump["name"], "display", "SIG{signal}");
        assert!(std::fs::metadata(&files.shot).unwrap().len() > 1000, "SIG{signal}: a screenshot");
        let log = std::fs::read_to_string(&files.log).unwrap();
        assert!(log.contains(r#""event":"load""#), "SIG{signal}: the trial log: {log}");
    }
}

#[test]
fn dump_root_display_shows_the_layouts_windows_as_they_were_at_exit() {
    let (mut child, _files) = mocu_run(&["--frames", "30"]);
    let err = lines(&mut child);
    let (status, stdout, stderr) = finish(child, &err, Vec::new());
    assert!(status.success(), "{stderr}");
    let dump: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let windows = windows_in(&dump);
    for w in ["video", "forward", "overlay"] {
        assert!(windows.iter().any(|x| x == w), "window `{w}` in {windows:?}");
    }
    assert!(windows.iter().any(|w| w == "strip@usv1"), "the first USV's strip: {windows:?}");
}

/// A run whose shutdown gets stuck on its outputs: `--screenshot` is a FIFO that nobody
/// reads, so writing it blocks for good (as a machine under heavy decoding or a stuck module
/// would hold a shutdown up, but deterministically).
fn stuck_run() -> (Child, crossbeam_channel::Receiver<String>, Vec<String>, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("shot.png");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success(), "mkfifo");
    let mut child = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["run", "layouts/fig3-multi-usv.mocu", "--headless", "--size", "640x360"])
        .args(["--mavlink", "off", "--video", "off", "--no-watch", "--screenshot"])
        .arg(&fifo)
        .env_remove("DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = lines(&mut child);
    let seen = wait_running(&err);
    (child, err, seen, dir)
}

fn signal(child: &Child, name: &str) {
    let status =
        Command::new("kill").args([&format!("-{name}"), &child.id().to_string()]).status().unwrap();
    assert!(status.success());
}

/// Waits for the line that says the signal was taken.
fn wait_stopping(err: &crossbeam_channel::Receiver<String>, seen: &mut Vec<String>) {
    loop {
        match err.recv_timeout(HANG) {
            Ok(l) => {
                let stopping = l.contains(": stopping");
                seen.push(l);
                if stopping {
                    return;
                }
            }
            Err(_) => panic!("the signal was not taken:\n{}", seen.join("\n")),
        }
    }
}

#[test]
fn a_second_sigint_exits_at_once_while_the_first_ones_shutdown_is_stuck() {
    use std::os::unix::process::ExitStatusExt;
    let (child, err, mut seen, _dir) = stuck_run();
    signal(&child, "INT");
    wait_stopping(&err, &mut seen);
    signal(&child, "INT");
    let (status, _, stderr) = finish(child, &err, seen);
    assert_eq!(status.code(), Some(130), "{status:?} {:?}\n{stderr}", status.signal());
    assert!(!stderr.contains("still stopping"), "the second signal, not the bound: {stderr}");
}

#[test]
fn the_shutdown_a_signal_starts_is_bounded_even_when_it_is_stuck() {
    let (child, err, mut seen, _dir) = stuck_run();
    signal(&child, "TERM");
    wait_stopping(&err, &mut seen);
    let (status, _, stderr) = finish(child, &err, seen);
    assert_eq!(status.code(), Some(143), "{status:?}\n{stderr}");
    assert!(stderr.contains("still stopping 20 s after SIGTERM"), "{stderr}");
}

//! The core modules of `mocu run` (input, the widget renderer, the map view, the video
//! windows) are modules like the others, end to end with the built binary: each starts by
//! default when the profile leaves its role empty, a profile puts another kind in a role or
//! turns a module off (`enabled = false`), and `mocu check` refuses an unknown kind or
//! setting naming the ones it knows (docs/modules.md, "Core modules and replacing them").

mod cli_support;

use cli_support::{mocu, scratch_dir};
use std::path::Path;

/// A project in `dir`: `modules` (TOML) as its modules, and one layout with a map window.
fn project(dir: &Path, modules: &str) -> String {
    std::fs::write(
        dir.join("chart.mocu"),
        "window chart {\n    type \"map\"\n    layer 1\n    rect 0 0 100% 100%\n}\n",
    )
    .unwrap();
    let profile = format!(
        "[profile]\nname = \"core\"\nscreen = [320, 200]\nlayouts = [\"chart.mocu\"]\n\n\
         [modules.sim]\nvehicles = [\"usv1\"]\n\n{modules}"
    );
    let path = dir.join("project.toml");
    std::fs::write(&path, profile).unwrap();
    path.display().to_string()
}

/// The modules `mocu run PROFILE` started: (name, kind) in start order, from `--dump
/// root.modules` (taken before the teardown).
fn started(profile: &str) -> Vec<(String, String)> {
    let out = mocu(&[
        "run",
        profile,
        "--headless",
        "--frames",
        "2",
        "--mavlink",
        "off",
        "--video",
        "off",
        "--no-watch",
        "--dump",
        "root.modules",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "mocu run {profile} failed:\n{stderr}");
    let dump: serde_json::Value = serde_json::from_slice(&out.stdout).expect("--dump is JSON");
    let children = dump["children"].as_array().expect("root.modules has children");
    children
        .iter()
        .map(|m| {
            assert_eq!(m["properties"]["state"], "running", "{m}\n{stderr}");
            let kind = m["properties"]["kind"].as_str().unwrap_or("?");
            (m["name"].as_str().unwrap().to_string(), kind.to_string())
        })
        .collect()
}

fn pairs(list: &[(&str, &str)]) -> Vec<(String, String)> {
    list.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect()
}

#[test]
fn the_core_modules_start_when_the_profile_does_not_list_them() {
    let dir = scratch_dir("core-modules", "defaults");
    let got = started(&project(&dir, ""));
    let want = [
        ("sim", "sim"),
        ("input", "input"),
        ("window_manager", "window_manager"),
        ("widgets", "widgets"),
        ("map_view", "map_view"),
        ("video_windows", "video_windows"),
    ];
    assert_eq!(got, pairs(&want));
}

#[test]
fn a_profile_puts_another_kind_in_a_role_or_turns_a_core_module_off() {
    let dir = scratch_dir("core-modules", "chosen");
    // The widget renderer under another name (its role is filled: no second one), the map
    // view off, the video windows configured; input as the default. The core modules start
    // after the others, input first.
    let modules = "[modules.hud]\nkind = \"widgets\"\naccepted_ms = 500\n\n\
                   [modules.map_view]\nenabled = false\n\n\
                   [modules.video_windows]\nstale_ms = 2000\n";
    let got = started(&project(&dir, modules));
    let want = [
        ("sim", "sim"),
        ("input", "input"),
        ("window_manager", "window_manager"),
        ("hud", "widgets"),
        ("video_windows", "video_windows"),
    ];
    assert_eq!(got, pairs(&want));
}

#[test]
fn check_refuses_an_unknown_kind_or_setting_of_a_core_module_naming_what_it_knows() {
    let dir = scratch_dir("core-modules", "check");
    let out = mocu(&["check", &project(&dir, "[modules.map_view]\nkind = \"map_veiw\"\n")]);
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("no module kind `map_veiw`"), "{text}");
    assert!(text.contains("did you mean `map_view`?"), "{text}");
    for kind in ["`widgets`", "`video_windows`", "`input`"] {
        assert!(text.contains(kind), "the kinds are listed: {text}");
    }

    let out = mocu(&["check", &project(&dir, "[modules.widgets]\nacepted_ms = 500\n")]);
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("the widgets module has no setting `acepted_ms`"), "{text}");
    assert!(text.contains("did you mean `accepted_ms`?"), "{text}");

    let fine = "[modules.map_view]\nenabled = false\n\n[modules.widgets]\nrefused_ms = 100\n";
    let out = mocu(&["check", &project(&dir, fine)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stdout));
}

/// Where window `a` is after `mocu run` presses S (`swap a b 400ms`) 50 ms in and stops
/// 20 frames (333 ms) in, with `modules` as the profile's modules: its `x` (b starts at 200).
fn swapped_x(name: &str, modules: &str) -> f64 {
    let dir = scratch_dir("core-modules", name);
    std::fs::write(
        dir.join("two.mocu"),
        "window a { layer 1 rect 0 0 100 100 }
window b { layer 2 rect 200 0 100 100 }
         bind keyboard { key s -> swap a b 400ms }
",
    )
    .unwrap();
    std::fs::write(
        dir.join("keys.script"),
        "0 kb connect keyboard \"Keys\"\n50 kb press s\n60 kb release s\n",
    )
    .unwrap();
    let profile = dir.join("project.toml");
    std::fs::write(
        &profile,
        format!(
            "[profile]\nname = \"wm\"\nscreen = [320, 200]\nlayouts = [\"two.mocu\"]\n\n{modules}"
        ),
    )
    .unwrap();
    let out = mocu(&[
        "run",
        &profile.display().to_string(),
        "--headless",
        "--no-sim",
        "--frames",
        "20",
        "--mavlink",
        "off",
        "--video",
        "off",
        "--no-watch",
        "--input-script",
        &dir.join("keys.script").display().to_string(),
        "--dump",
        "root.display.a",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let a: serde_json::Value = serde_json::from_slice(&out.stdout).expect("--dump is JSON");
    a["properties"]["x"].as_f64().unwrap_or_else(|| panic!("no x: {a}\n{stderr}"))
}

#[test]
fn the_window_manager_module_animates_a_swap_and_a_profile_can_make_it_instant_or_turn_it_off() {
    let animated = swapped_x("wm-default", "");
    assert!(
        animated > 20.0 && animated < 190.0,
        "about 280 ms into a 400 ms swap: on its way, at {animated}"
    );
    let instant = swapped_x("wm-instant", "[modules.window_manager]\nanimate = false\n");
    assert_eq!(instant, 200.0, "animate = false: at once");
    // Without a window manager, the layout's swap exchanges the places itself, at once.
    let off = swapped_x("wm-off", "[modules.window_manager]\nenabled = false\n");
    assert_eq!(off, 200.0);
}

//! The `penumbra` binary: the default scene works from any directory, and bad
//! input gives one clear line on stderr and a non-zero exit code.

use std::path::Path;
use std::process::{Command, Output};

fn penumbra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        // The built-in scene must not depend on the working directory.
        .current_dir(env!("CARGO_TARGET_TMPDIR"))
        .output()
        .expect("the penumbra binary runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn info_on_the_default_scene() {
    let out = penumbra(&["info"]);
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for field in [
        "triangles",
        "nodes",
        "leaves",
        "leaf sizes",
        "max depth",
        "SAH cost",
        "build",
        "bounds",
    ] {
        assert!(stdout.contains(field), "no '{field}' in:\n{stdout}");
    }
    assert!(stdout.contains("playground"), "{stdout}");
}

#[test]
fn info_on_each_builtin_scene_by_name() {
    for s in penumbra::assets::EMBEDDED_SCENES {
        let out = penumbra(&["info", s.name, "--leaf-size", "8", "--quality", "fast"]);
        assert!(out.status.success(), "{}: {}", s.name, text(&out.stderr));
        assert!(text(&out.stdout).contains("max leaf size 8"));
    }
}

/// `info` counts the alpha-tested triangles (the screen's two; none in the playground),
/// and exact visibility, which clips polygons, refuses a scene with masks in one line.
#[test]
fn alpha_masks_are_counted_and_refused_where_they_cannot_be_traced() {
    let out = penumbra(&["info", "screen"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("alpha      2 alpha-tested triangle(s)"),
        "{}",
        text(&out.stdout)
    );
    let out = penumbra(&["info"]);
    assert!(
        text(&out.stdout).contains("alpha      0 alpha-tested triangle(s)"),
        "{}",
        text(&out.stdout)
    );
    let out = penumbra(&[
        "render",
        "screen",
        "--tracer",
        "exact",
        "--size",
        "8x8",
        "-o",
        "exact.exr",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("2 alpha-tested triangles") && stderr.contains("reference"),
        "{stderr}"
    );
    assert!(!Path::new(env!("CARGO_TARGET_TMPDIR")).join("exact.exr").exists());
}

#[test]
fn missing_file_is_one_line_and_exit_1() {
    let out = penumbra(&["info", "/no/such/scene.glb"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: /no/such/scene.glb:"), "{stderr}");
}

/// Every command that writes a file refuses a path into a folder that does not exist
/// before it does any work (a quality run can take many minutes): one line, exit 1,
/// nothing on stdout.
#[test]
fn outputs_into_missing_folders_are_refused_before_any_work() {
    let (json, diff) = ("/no/such/folder/out.json", "/no/such/folder/diff.png");
    for args in [
        vec!["render", "--size", "8x8", "--output", "/no/such/folder/out.png"],
        vec!["bench", "--size", "8x8", "--json", json],
        vec!["quality", "--size", "8x8", "--json", json],
        vec!["compare", "a.png", "b.png", "--diff", diff],
    ] {
        let out = penumbra(&args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("error: /no/such/folder/")
                && stderr.contains("cannot write there: the folder /no/such/folder does not exist"),
            "{args:?}: {stderr}"
        );
        assert!(out.stdout.is_empty(), "{args:?}: {}", text(&out.stdout));
    }
}

#[test]
fn malformed_file_names_the_file_and_the_problem() {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_truncated.glb");
    let glb = penumbra::assets::default_scene().glb;
    std::fs::write(&path, &glb[..glb.len() / 2]).unwrap();
    let out = penumbra(&["info", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("cli_truncated.glb") && stderr.contains("truncated"),
        "{stderr}"
    );
}

#[test]
fn bad_flags_are_usage_errors() {
    let out = penumbra(&["info", "--leaf-size", "0"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "clap reports usage errors with code 2"
    );
    let help = penumbra(&["--help"]);
    assert!(help.status.success());
    assert!(text(&help.stdout).contains("info"));
}

#[test]
fn verbose_adds_the_source_chain_and_detail() {
    let quiet = penumbra(&["info", "/no/such/scene.glb"]);
    let io = std::fs::read("/no/such/scene.glb").unwrap_err();
    assert_eq!(text(&quiet.stderr), format!("error: /no/such/scene.glb: {io}\n"));
    // A global flag: before or after the subcommand.
    for args in [
        ["info", "/no/such/scene.glb", "--verbose"],
        ["--verbose", "info", "/no/such/scene.glb"],
    ] {
        let out = penumbra(&args);
        assert_eq!(out.status.code(), Some(1));
        let stderr = text(&out.stderr);
        let lines: Vec<&str> = stderr.lines().collect();
        assert_eq!(lines.len(), 3, "{stderr}");
        assert_eq!(lines[0], format!("error: /no/such/scene.glb: {io}"));
        assert_eq!(lines[1], format!("caused by: {io}"));
        assert!(
            lines[2].starts_with("detail: Io { path: \"/no/such/scene.glb\", source: Os {"),
            "{stderr}"
        );
    }
}

#[test]
fn bad_views_are_one_line_naming_the_file_and_field() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_views");
    std::fs::create_dir_all(&dir).unwrap();
    let camera = r#""camera": {"eye": [0, 5, 9], "target": [0, 0, 0], "fov_y_degrees": 50}"#;
    for (name, json, message) in [
        (
            "flat_light.json",
            format!(
                r#"{{{camera}, "light": {{"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [3, 0, 0]}}}}"#
            ),
            "light has zero area: |edge_u × edge_v| = 0 (edge_u [1, 0, 0] and edge_v [3, 0, 0] are zero, \
             parallel or too short)",
        ),
        (
            "dark_light.json",
            format!(
                r#"{{{camera}, "light": {{"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1], "intensity": -2}}}}"#
            ),
            "light.intensity is -2, must not be negative",
        ),
        (
            "far_eye.json",
            r#"{"camera": {"eye": [0, 5e38, 9], "target": [0, 0, 0], "fov_y_degrees": 50},
                "light": {"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]}}"#
                .to_owned(),
            "camera.eye [0, inf, 9] is not finite",
        ),
        (
            "no_lights.json",
            format!(r#"{{{camera}, "lights": []}}"#),
            r#""lights" is empty: give at least one light"#,
        ),
        (
            "light_and_lights.json",
            format!(
                r#"{{{camera}, "light": {{"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]}},
                    "lights": [{{"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]}}]}}"#
            ),
            r#"has both "light" and "lights"; give one light or a list of lights"#,
        ),
        (
            "flat_second_light.json",
            format!(
                r#"{{{camera}, "lights": [{{"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]}},
                    {{"corner": [0, 9, 0], "edge_u": [1, 0, 0], "edge_v": [3, 0, 0]}}]}}"#
            ),
            "lights[1]: light has zero area: |edge_u × edge_v| = 0 (edge_u [1, 0, 0] and edge_v [3, 0, 0] \
             are zero, parallel or too short)",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, json).unwrap();
        // The view is checked before any GPU work, so this needs no adapter.
        let out = penumbra(&["render", "--view", path.to_str().unwrap(), "-o", "never.png"]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        assert_eq!(
            text(&out.stderr),
            format!("error: {}: {message}\n", path.display()),
            "{name}"
        );
    }
}

#[test]
fn info_reports_gpu_memory_for_a_size() {
    let out = penumbra(&["info"]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("GPU memory"), "{stdout}");
    assert!(
        stdout.contains("  frame      191.00 MiB for 1024x1024 (G-buffer 64.00 MiB, "),
        "{stdout}"
    );
    let out = penumbra(&["info", "lattice", "--size", "7x1"]);
    assert!(out.status.success());
    let stdout = text(&out.stdout);
    let frame = stdout.lines().find(|l| l.starts_with("  frame")).unwrap();
    assert!(
        frame.contains("for 7x1 (G-buffer 448 B, shadow masks 28 B,"),
        "{frame}"
    );
    let scene = stdout.lines().find(|l| l.starts_with("  scene")).unwrap();
    assert!(
        scene.contains("BVH nodes") && scene.contains("texels 16 B"),
        "{scene}"
    );
    let out = penumbra(&["info", "--size", "0x5"]);
    assert_eq!(out.status.code(), Some(2), "a usage error");
}

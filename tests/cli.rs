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

#[test]
fn missing_file_is_one_line_and_exit_1() {
    let out = penumbra(&["info", "/no/such/scene.glb"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: /no/such/scene.glb:"), "{stderr}");
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

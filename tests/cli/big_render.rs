//! A 4096×4096 render on lavapipe: its buffers exceed one storage-buffer binding
//! (128 MiB there), so the renderer tiles it; the file comes out whole.

use std::path::Path;
use std::process::Command;

#[test]
fn a_4096_square_render_completes_in_tiles() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_big_render");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "--size", "4096x4096", "-o", "big.png"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = penumbra::output::read_hdr_image(&dir.join("big.png")).unwrap();
    assert_eq!((image.width, image.height), (4096, 4096));
    let lit = image.pixels.iter().filter(|p| p[0] > 0.0).count();
    assert!(
        lit > image.pixels.len() / 4,
        "the image has content: {lit} lit pixels"
    );
    println!("{stdout}");
}

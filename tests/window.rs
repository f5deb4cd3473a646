//! The windowed target under Xvfb on lavapipe: the demo opens a window,
//! renders and presents frames with validation on, and closes cleanly.
//! Needs Xvfb (tools/test.sh installs it); set INLAY_SKIP_WINDOW_TESTS=1 to
//! skip on a machine without it.

mod common;

use std::process::{Child, Command, Stdio};
use std::time::Duration;

struct Xvfb(Child);

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn start_xvfb() -> Option<(Xvfb, String)> {
    if std::env::var_os("INLAY_SKIP_WINDOW_TESTS").is_some() {
        return None;
    }
    for n in 90..120 {
        let display = format!(":{n}");
        if std::path::Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
            continue;
        }
        let child = Command::new("Xvfb")
            .args([
                display.as_str(),
                "-screen",
                "0",
                "640x480x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn();
        let child = child.unwrap_or_else(|e| panic!("Xvfb is needed for window tests (tools/test.sh installs it; INLAY_SKIP_WINDOW_TESTS=1 skips): {e}"));
        let server = Xvfb(child);
        for _ in 0..50 {
            if std::path::Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                return Some((server, display));
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
    panic!("could not start Xvfb on displays :90-:119");
}

#[test]
fn demo_window_presents_frames_with_validation_clean() {
    let Some((_server, display)) = start_xvfb() else {
        return;
    };
    let o = Command::new(env!("CARGO_BIN_EXE_inlay"))
        .env("DISPLAY", &display)
        .args([
            "--validate",
            "demo",
            "--frames",
            "40",
            "--width",
            "160",
            "--height",
            "120",
            "--present-mode",
            "mailbox",
        ])
        .output()
        .unwrap();
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("window: inlay demo on"), "{t}");
    assert!(!t.contains("rendering headless instead"), "{t}");
    for pass in ["sky", "quads", "scene", "present"] {
        assert!(t.contains(pass), "final timing table lacks {pass}: {t}");
    }
    assert!(
        !t.contains("readback"),
        "the window path presents, it does not read back: {t}"
    );
}

#[test]
fn without_a_display_the_demo_falls_back_to_headless() {
    let dir = std::env::temp_dir().join(format!("inlay-nodisplay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("fallback.png");
    let o = Command::new(env!("CARGO_BIN_EXE_inlay"))
        .env_remove("DISPLAY")
        .args([
            "demo",
            "--frames",
            "1",
            "--width",
            "16",
            "--height",
            "16",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let t = common::output_text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("rendering headless instead") && out.exists(),
        "{t}"
    );
}

//! The windowed target under Xvfb on lavapipe: the demo opens a window,
//! renders and presents frames with validation on, and closes cleanly.
//! Needs Xvfb (tools/test.sh installs it); set INLAY_SKIP_WINDOW_TESTS=1 to
//! skip on a machine without it.

mod common;

use std::process::{Child, Command, Stdio};
use std::time::Duration;

struct Xvfb(Child);

impl Drop for Xvfb {
    /// Terminates the server so that it removes its lock and socket (a
    /// killed one leaves them, and the display numbers run out).
    fn drop(&mut self) {
        let terminated = Command::new("kill")
            .arg(self.0.id().to_string())
            .status()
            .is_ok_and(|s| s.success());
        if terminated {
            for _ in 0..50 {
                if matches!(self.0.try_wait(), Ok(Some(_))) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
        }
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Whether display `n` is taken: its lock names a running process (a
/// lock or socket a dead server left behind is removed).
fn display_taken(n: u32) -> bool {
    let lock = format!("/tmp/.X{n}-lock");
    let socket = format!("/tmp/.X11-unix/X{n}");
    match std::fs::read_to_string(&lock) {
        Ok(pid) => {
            let alive = pid
                .trim()
                .parse::<u32>()
                .is_ok_and(|pid| std::path::Path::new(&format!("/proc/{pid}")).exists());
            if alive {
                return true;
            }
            // Left by a server that is gone: clear it, or count it taken.
            let _ = std::fs::remove_file(&socket);
            std::fs::remove_file(&lock).is_err() || std::path::Path::new(&socket).exists()
        }
        Err(_) => std::path::Path::new(&socket).exists(),
    }
}

fn start_xvfb() -> Option<(Xvfb, String)> {
    if std::env::var_os("INLAY_SKIP_WINDOW_TESTS").is_some() {
        return None;
    }
    // Tests run in parallel threads: each takes its own display number
    // (two servers racing for one left one test drawing on the other's).
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(90);
    loop {
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        if n >= 120 {
            break;
        }
        let display = format!(":{n}");
        if display_taken(n) {
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
            "fifo",
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

/// The viewer driven like a user: open `inlay view` on DOG under Xvfb with
/// validation, wait for its first frame, screenshot, drag the object with
/// injected (XTEST) mouse input to another spot on the floor, wait for a
/// frame showing the move, screenshot again, switch the quality preset
/// with F5 (the passes rebuilt over the same field upload) and draw on,
/// resize the window and draw on at the new size, hide and show it, quit
/// with Escape. The object must have moved (it says where, and the
/// image changed around its old and new pixels), the image must not be
/// blank, and the run must be validation-clean.
#[test]
fn the_viewer_moves_the_object_where_it_is_dragged() {
    use std::io::BufRead;
    use std::sync::mpsc;
    use x11rb::connection::Connection;
    use x11rb::protocol::xproto::ConnectionExt as _;
    use x11rb::protocol::xtest::ConnectionExt as _;

    let Some((_server, display)) = start_xvfb() else {
        return;
    };
    let (w, h) = (320u16, 180u16);
    let mut app = Command::new(env!("CARGO_BIN_EXE_inlay"))
        .env("DISPLAY", &display)
        .args(["--validate", "view"])
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/dog.toml"))
        .args([
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--preset",
            "fast",
            "--overlay",
            "compact",
            // The default present mode (FIFO): an earlier stall seen with
            // it was two tests sharing one Xvfb display.
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Drain stderr as it comes: a full pipe would block the viewer.
    let stderr = app.stderr.take().unwrap();
    let stderr_text = std::thread::spawn(move || {
        let mut err = String::new();
        let _ = std::io::Read::read_to_string(&mut std::io::BufReader::new(stderr), &mut err);
        err
    });
    let (tx, rx) = mpsc::channel::<String>();
    let stdout = app.stdout.take().unwrap();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
        {
            eprintln!("viewer: {line}");
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut log = String::new();
    let mut wait_for = |needle: &str, secs: u64| -> String {
        let deadline = std::time::Instant::now() + Duration::from_secs(secs);
        while let Some(left) = deadline.checked_duration_since(std::time::Instant::now()) {
            match rx.recv_timeout(left) {
                Ok(line) => {
                    log.push_str(&line);
                    log.push('\n');
                    if line.contains(needle) {
                        return line;
                    }
                }
                Err(_) => break,
            }
        }
        panic!("no `{needle}` within {secs} s; output so far:\n{log}");
    };
    let pixel = |line: &str| -> (f64, f64) {
        let s = &line[line.rfind('(').unwrap() + 1..line.rfind(')').unwrap()];
        let v: Vec<f64> = s.split(", ").map(|x| x.parse().unwrap()).collect();
        (v[0], v[1])
    };
    let first = wait_for("first frame presented; object `silver-ball` at pixel", 600);
    let old = pixel(&first);
    let (conn, screen) = x11rb::connect(Some(&display)).unwrap();
    let root = conn.setup().roots[screen].root;
    let shot = |conn: &x11rb::rust_connection::RustConnection| -> Vec<[u8; 3]> {
        let img = conn
            .get_image(
                x11rb::protocol::xproto::ImageFormat::Z_PIXMAP,
                root,
                0,
                0,
                w,
                h,
                !0,
            )
            .unwrap()
            .reply()
            .unwrap();
        assert_eq!(img.data.len(), w as usize * h as usize * 4, "24-bit screen");
        img.data.chunks(4).map(|p| [p[2], p[1], p[0]]).collect()
    };
    std::thread::sleep(Duration::from_secs(2));
    let before = shot(&conn);
    // Drag from the object to a spot on the floor, down and to the left.
    let target = (old.0 - 0.22 * w as f64, old.1 + 0.12 * h as f64);
    let motion = |x: f64, y: f64| {
        conn.xtest_fake_input(6, 0, 0, root, x as i16, y as i16, 0)
            .unwrap();
        conn.flush().unwrap();
        std::thread::sleep(Duration::from_millis(100));
    };
    motion(old.0, old.1);
    conn.xtest_fake_input(4, 1, 0, root, 0, 0, 0).unwrap();
    for k in 1..=10 {
        let t = k as f64 / 10.0;
        motion(
            old.0 + t * (target.0 - old.0),
            old.1 + t * (target.1 - old.1),
        );
    }
    conn.xtest_fake_input(5, 1, 0, root, 0, 0, 0).unwrap();
    conn.flush().unwrap();
    let moved = wait_for("view: moved `silver-ball`", 120);
    let new = pixel(&moved);
    wait_for("shows", 300);
    std::thread::sleep(Duration::from_secs(2));
    let after = shot(&conn);
    // Without a window manager nothing gives the window keyboard focus:
    // give it, as a window manager would on a click.
    let windows = conn.query_tree(root).unwrap().reply().unwrap().children;
    let viewer_window = windows
        .into_iter()
        .rev()
        .find(|&w| {
            conn.get_window_attributes(w)
                .unwrap()
                .reply()
                .is_ok_and(|a| a.map_state == x11rb::protocol::xproto::MapState::VIEWABLE)
        })
        .expect("the viewer's window is mapped");
    let focus = || {
        conn.set_input_focus(
            x11rb::protocol::xproto::InputFocus::PARENT,
            viewer_window,
            x11rb::CURRENT_TIME,
        )
        .unwrap();
    };
    focus();
    // F5 (keycode 71) rebuilds the passes at the next preset, keeping the
    // moved object; Escape (keycode 9 in the server's default map) closes
    // the viewer.
    conn.xtest_fake_input(2, 71, 0, root, 0, 0, 0).unwrap();
    conn.xtest_fake_input(3, 71, 0, root, 0, 0, 0).unwrap();
    conn.flush().unwrap();
    wait_for("view: quality preset balanced", 300);
    wait_for("fps average", 300);
    // Resizing the window (as a window manager would) recreates the
    // swapchain: frames go on at the new size.
    conn.configure_window(
        viewer_window,
        &x11rb::protocol::xproto::ConfigureWindowAux::new()
            .width(400)
            .height(200),
    )
    .unwrap();
    conn.flush().unwrap();
    wait_for("fps average, 400x200", 300);
    // Hidden and shown again (what minimising and restoring do to an X11
    // window without a window manager): the viewer draws on.
    conn.unmap_window(viewer_window).unwrap();
    conn.flush().unwrap();
    std::thread::sleep(Duration::from_secs(1));
    conn.map_window(viewer_window).unwrap();
    conn.flush().unwrap();
    wait_for("fps average, 400x200", 300);
    focus();
    conn.xtest_fake_input(2, 9, 0, root, 0, 0, 0).unwrap();
    conn.xtest_fake_input(3, 9, 0, root, 0, 0, 0).unwrap();
    conn.flush().unwrap();
    let quit_by = std::time::Instant::now() + Duration::from_secs(120);
    let status = loop {
        if let Some(status) = app.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() > quit_by {
            let _ = app.kill();
            panic!("the viewer did not close within 120 s of Escape\n{log}");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let err = stderr_text.join().unwrap();
    assert!(status.success(), "viewer failed: {err}\n{log}");
    assert!(
        !err.contains("VUID") && !err.to_lowercase().contains("validation error"),
        "{err}"
    );

    let dist = ((new.0 - old.0).powi(2) + (new.1 - old.1).powi(2)).sqrt();
    assert!(
        dist > 20.0,
        "object moved only {dist:.1} px: {old:?} -> {new:?}\n{log}"
    );
    let change_near = |c: (f64, f64)| -> f64 {
        let mut sum = 0.0f64;
        let mut n = 0.0f64;
        for y in (c.1 as i64 - 4)..=(c.1 as i64 + 4) {
            for x in (c.0 as i64 - 4)..=(c.0 as i64 + 4) {
                if x >= 0 && y >= 0 && x < w as i64 && y < h as i64 {
                    let i = (y * w as i64 + x) as usize;
                    sum += (0..3)
                        .map(|k| (before[i][k] as f64 - after[i][k] as f64).abs())
                        .sum::<f64>()
                        / 3.0;
                    n += 1.0;
                }
            }
        }
        sum / n.max(1.0)
    };
    write_screenshot_ppm("window-test-before.ppm", &before, w as usize, h as usize);
    write_screenshot_ppm("window-test-after.ppm", &after, w as usize, h as usize);
    let (at_old, at_new) = (change_near(old), change_near(new));
    eprintln!("object {old:?} -> {new:?}; mean change {at_old:.1} at the old pixel, {at_new:.1} at the new");
    assert!(
        at_old > 8.0 && at_new > 8.0,
        "old {at_old:.1}, new {at_new:.1}"
    );
    let luma: Vec<f64> = after
        .iter()
        .map(|p| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64)
        .collect();
    let mean = luma.iter().sum::<f64>() / luma.len() as f64;
    let sd = (luma.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / luma.len() as f64).sqrt();
    assert!(
        sd > 10.0 && mean > 10.0,
        "blank screenshot: mean {mean:.1}, sd {sd:.1}"
    );
}

/// Keeps a viewer screenshot for inspection (target/`name`).
fn write_screenshot_ppm(name: &str, pixels: &[[u8; 3]], w: usize, h: usize) {
    let mut bytes = format!("P6\n{w} {h}\n255\n").into_bytes();
    bytes.extend(pixels.iter().flatten());
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join(name);
    let _ = std::fs::write(path, bytes);
}

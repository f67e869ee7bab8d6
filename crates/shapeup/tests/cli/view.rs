//! `shapeup view --screenshot`: one headless frame of the real renderer (needs a GPU adapter;
//! Mesa's software rasterizers count, as in CI).

use std::process::Command;

fn shapeup() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shapeup"))
}

fn data(name: &str) -> String {
    format!("{}/../../data/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Decodes an RGBA8 PNG.
fn read_png(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn screenshot_shows_the_mesh_centred_on_a_white_background() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("spot.png");
    let status = shapeup()
        .args(["view", &data("spot.obj"), "--screenshot"])
        .arg(&out)
        .args(["--size", "320x240"])
        .status()
        .unwrap();
    assert!(status.success());
    let (w, h, px) = read_png(&out);
    assert_eq!((w, h), (320, 240));
    let pixel = |x: u32, y: u32| &px[((y * w + x) * 4) as usize..((y * w + x) * 4 + 3) as usize];
    // Corners are background; the mesh covers a good part of the frame, including its centre.
    assert_eq!(pixel(0, 0), [255, 255, 255]);
    assert_eq!(pixel(w - 1, h - 1), [255, 255, 255]);
    let covered =
        (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| pixel(x, y) != [255, 255, 255]).count();
    let fraction = covered as f64 / f64::from(w * h);
    assert!((0.05..0.9).contains(&fraction), "mesh covers {fraction:.3} of the frame");
    assert_ne!(pixel(w / 2, h / 2), [255, 255, 255], "the mesh is framed at the centre");
}

#[test]
fn screenshot_of_a_scene_shows_the_solved_shape_with_handles() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "[mesh]\npath = \"{}\"\n[[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\n\
             box = {{ min = [-1, -1, -1], max = [1, -0.6, 2] }}\n",
            data("spot.obj")
        ),
    )
    .unwrap();
    let out = dir.path().join("scene.png");
    let status = shapeup()
        .args(["view"])
        .arg(&scene)
        .arg("--screenshot")
        .arg(&out)
        .args(["--size", "200x200"])
        .status()
        .unwrap();
    assert!(status.success());
    let (_, _, px) = read_png(&out);
    // The fixed feet are drawn in the handle green.
    let green = px.chunks(4).filter(|p| p[1] > 120 && p[0] < 80 && p[2] < 100).count();
    assert!(green > 20, "{green} handle pixels");
}

#[test]
fn bad_screenshot_requests_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.jpg");
    let o = shapeup().args(["view", &data("spot.obj"), "--screenshot"]).arg(&out).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains(".png"));
    let o = shapeup().args(["view", "no-such.obj", "--screenshot"]).arg(dir.path().join("a.png")).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no-such.obj"));
    assert!(!dir.path().join("a.png").exists());
}

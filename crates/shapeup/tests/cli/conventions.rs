//! The command line's conventions: log levels (-q, -v, RUST_LOG), TetGen's output kept off
//! stdout, progress bars only on a terminal, shell completions and manual pages, the bundled
//! samples (from a folder that is not the repository) and `shapeup info`.

use shapeup_core::io::read_mesh;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::Output;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data");

fn data(name: &str) -> PathBuf {
    Path::new(DATA).join(name)
}

/// `shapeup ARGS…` from `cwd`, with no RUST_LOG from the environment unless `env` sets one.
fn run_in<S: AsRef<OsStr>>(cwd: &Path, args: &[S], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_shapeup"));
    cmd.args(args).current_dir(cwd).env_remove("RUST_LOG");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().unwrap();
    Output {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A failure as the contract says: non-zero exit, one line on stderr naming `what`, no stdout.
fn assert_one_line_failure(out: &Output, what: &str) {
    assert_ne!(out.code, Some(0), "{}", out.describe());
    assert!(out.stdout.is_empty(), "nothing on stdout\n{}", out.describe());
    assert_eq!(out.stderr.lines().count(), 1, "one line\n{}", out.describe());
    assert!(out.stderr.starts_with("shapeup: error: ") && out.stderr.contains(what), "{}", out.describe());
    assert!(!out.stderr.contains("panicked"), "{}", out.describe());
}

/// --threads takes a whole number from 1 to 1024: a negative one is named as a bad value (not
/// taken for an unknown flag), as are 0, words and too many; so is a negative value of every
/// other count (--frames, --every, --iterations, …). One line, no output.
#[test]
fn a_bad_count_is_named_with_its_flag() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = data("spot.obj");
    for bad in ["-1", "0", "abc", "5000"] {
        let out =
            run_in(dir.path(), &[OsStr::new("--threads"), OsStr::new(bad), OsStr::new("info"), mesh.as_os_str()], &[]);
        assert_one_line_failure(&out, "--threads");
        assert!(out.stderr.contains(bad) && out.stderr.contains("1 to 1024"), "{}", out.describe());
    }
    // Every count a command takes: a negative one names its flag too.
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "[mesh]\ngenerate = { kind = \"cloth\", vertices = [3, 3], size = [1.0, 1.0] }\n[[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n").unwrap();
    let out_dir = dir.path().join("out");
    let s = scene.as_os_str();
    let o = out_dir.as_os_str();
    for (args, flag) in [
        (vec![OsStr::new("simulate"), s, "--frames".as_ref(), "-1".as_ref(), "-o".as_ref(), o], "--frames"),
        (vec![OsStr::new("simulate"), s, "--every".as_ref(), "-1".as_ref(), "-o".as_ref(), o], "--every"),
        (vec![OsStr::new("deform"), s, "--iterations".as_ref(), "-1".as_ref(), "-o".as_ref(), o], "--iterations"),
        (vec![OsStr::new("deform"), s, "--lbfgs-memory".as_ref(), "-1".as_ref(), "-o".as_ref(), o], "--lbfgs-memory"),
        (vec![OsStr::new("bench"), "--iterations".as_ref(), "-1".as_ref()], "--iterations"),
    ] {
        let out = run_in(dir.path(), &args, &[]);
        assert_one_line_failure(&out, flag);
        assert!(out.stderr.contains("'-1'") && out.stderr.contains("found -1"), "{}", out.describe());
        assert!(!out.stderr.contains("invalid digit"), "{}", out.describe());
        assert!(!out_dir.exists(), "no output\n{}", out.describe());
    }
    // Out of range or not a number: the range in words (not clap's 1..18446744073709551615).
    for (args, said) in [
        (vec![OsStr::new("simulate"), s, "--frames".as_ref(), "0".as_ref(), "-o".as_ref(), o], "≥ 1, found 0"),
        (vec![OsStr::new("simulate"), s, "--every".as_ref(), "0".as_ref(), "-o".as_ref(), o], "≥ 1, found 0"),
        (
            vec![OsStr::new("deform"), s, "--anderson-window".as_ref(), "51".as_ref(), "-o".as_ref(), o],
            "from 1 to 50, found 51",
        ),
        (
            vec![OsStr::new("deform"), s, "--iterations".as_ref(), "ten".as_ref(), "-o".as_ref(), o],
            "whole number, found \"ten\"",
        ),
    ] {
        let out = run_in(dir.path(), &args, &[]);
        assert_one_line_failure(&out, said);
        assert!(!out.stderr.contains("18446744073709551615"), "{}", out.describe());
        assert!(!out_dir.exists(), "no output\n{}", out.describe());
    }
    // A folder where a mesh file is wanted is named as one (it used to be an unsupported
    // format "").
    std::fs::create_dir(dir.path().join("folder")).unwrap();
    let out = run_in(dir.path(), &[OsStr::new("deform"), s, "-o".as_ref(), "folder".as_ref()], &[]);
    assert_one_line_failure(&out, "folder: is a folder; give a file name in it, such as folder/result.obj");
}

/// RAYON_NUM_THREADS, which sizes the pool when --threads is not given, is checked as --threads
/// is (one line naming it, no output); more threads than cores is said once.
#[test]
fn the_thread_count_from_the_environment_is_checked_and_oversubscription_said() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = data("spot.obj");
    for bad in ["abc", "-1", "5000"] {
        let out = run_in(dir.path(), &[OsStr::new("info"), mesh.as_os_str()], &[("RAYON_NUM_THREADS", bad)]);
        assert_one_line_failure(&out, "RAYON_NUM_THREADS");
        assert!(out.stderr.contains(bad), "{}", out.describe());
    }
    let ok = run_in(dir.path(), &[OsStr::new("info"), mesh.as_os_str()], &[("RAYON_NUM_THREADS", "1")]);
    assert_eq!(ok.code, Some(0), "{}", ok.describe());
    assert!(ok.stderr.is_empty(), "{}", ok.describe());
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let many = (cores + 1).to_string();
    let out =
        run_in(dir.path(), &[OsStr::new("--threads"), OsStr::new(&many), OsStr::new("info"), mesh.as_os_str()], &[]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let line = format!("{many} threads on {cores} cores");
    assert_eq!(out.stderr.matches(&line).count(), 1, "{}", out.describe());
    assert!(out.stderr.contains(&format!("give --threads {cores} or fewer")), "{}", out.describe());
    // From the variable, the advice names the variable.
    let out = run_in(dir.path(), &[OsStr::new("info"), mesh.as_os_str()], &[("RAYON_NUM_THREADS", &many)]);
    assert!(out.stderr.contains(&format!("set RAYON_NUM_THREADS to {cores} or fewer")), "{}", out.describe());
    // Commands that compute nothing do not read it.
    for args in [vec!["types"], vec!["samples"], vec!["man"], vec!["completions", "bash"]] {
        let out = run_in(dir.path(), &args, &[("RAYON_NUM_THREADS", "abc")]);
        assert_eq!(out.code, Some(0), "{args:?}: {}", out.describe());
        assert!(out.stderr.is_empty(), "{args:?}: {}", out.describe());
    }
}

/// The subcommand names `shapeup --help` lists (so that new ones are covered without a list
/// kept here).
fn subcommands(dir: &Path) -> Vec<String> {
    let help = run_in(dir, &["--help"], &[]).success().stdout;
    let names: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|n| n != "help")
        .collect();
    for expected in ["deform", "simulate", "info", "samples", "completions", "man", "bench"] {
        assert!(names.iter().any(|n| n == expected), "{expected} in {names:?}");
    }
    names
}

// ---------------------------------------------------------------------------------------------
// Logs
// ---------------------------------------------------------------------------------------------

/// A scene on the beetle whose STL output draws two warnings (attributes and vertices lost).
fn beetle_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("beetle.toml");
    std::fs::write(
        &scene,
        format!(
            "[mesh]\npath = '{}'\n[solver]\niterations = 3\n[[constraints]]\ntype = \"edge_spring\"\n\
             [[constraints]]\ntype = \"position\"\nbox = {{ min = [-100, -100, -100], max = [100, 100, 100] }}\n",
            data("beetle.obj").display()
        ),
    )
    .unwrap();
    scene
}

#[test]
fn warnings_show_by_default_quiet_silences_them_and_verbose_adds_info() {
    let dir = tempfile::tempdir().unwrap();
    let scene = beetle_scene(dir.path());
    let deform = |flags: &[&str], env: &[(&str, &str)]| {
        let mut args: Vec<&OsStr> = flags.iter().map(OsStr::new).collect();
        args.extend([OsStr::new("deform"), scene.as_os_str(), OsStr::new("-o"), OsStr::new("out.stl")]);
        run_in(dir.path(), &args, env).success()
    };
    let plain = deform(&[], &[]);
    let warnings: Vec<&str> = plain.stderr.lines().collect();
    assert_eq!(warnings.len(), 2, "{}", plain.describe());
    assert!(
        warnings.iter().all(|l| l.starts_with("shapeup: warning: out.stl: ")),
        "the documented format: {warnings:?}"
    );
    assert!(plain.stdout.starts_with("deformed 1148 vertices"), "{}", plain.describe());

    let quiet = deform(&["-q"], &[]);
    assert!(quiet.stderr.is_empty(), "-q: errors only\n{}", quiet.describe());
    assert_eq!(quiet.stdout.lines().count(), 1, "the result line stays\n{}", quiet.describe());
    let quiet = deform(&["--quiet"], &[("RUST_LOG", "error")]);
    assert!(quiet.stderr.is_empty(), "{}", quiet.describe());
    let filtered = deform(&[], &[("RUST_LOG", "error")]);
    assert!(filtered.stderr.is_empty(), "RUST_LOG=error silences warnings\n{}", filtered.describe());

    let verbose = deform(&["-v"], &[]);
    assert!(verbose.stderr.lines().any(|l| l.starts_with("shapeup: info: ")), "{}", verbose.describe());
    assert_eq!(verbose.stderr.matches("shapeup: warning: ").count(), 2, "{}", verbose.describe());
    let by_env = deform(&[], &[("RUST_LOG", "info")]);
    assert!(by_env.stderr.lines().any(|l| l.starts_with("shapeup: info: ")), "{}", by_env.describe());
    // -v beats RUST_LOG's default level.
    let both = deform(&["-v"], &[("RUST_LOG", "error")]);
    assert!(both.stderr.contains("shapeup: info: "), "{}", both.describe());

    let conflict = run_in(dir.path(), &["-q", "-v", "types"], &[]);
    assert_eq!(conflict.code, Some(2), "-q and -v conflict\n{}", conflict.describe());
}

#[test]
fn errors_stay_one_line_whatever_the_log_level() {
    let dir = tempfile::tempdir().unwrap();
    for flags in [&[][..], &["-q"], &["-vvv"]] {
        let mut args: Vec<&str> = flags.to_vec();
        args.extend(["info", "no-such-mesh.ply"]);
        let out = run_in(dir.path(), &args, &[]);
        assert_one_line_failure(&out, "no-such-mesh.ply");
    }
}

// ---------------------------------------------------------------------------------------------
// TetGen
// ---------------------------------------------------------------------------------------------

/// A scene that asks TetGen to fill two overlapping closed tetrahedra (a self-intersecting
/// surface), which it refuses.
#[cfg(feature = "tetgen")]
#[test]
fn a_surface_tetgen_refuses_is_one_line_on_stderr_and_nothing_on_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let mut obj = String::new();
    for o in [0.0, 0.2] {
        for [x, y, z] in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            obj += &format!("v {} {} {}\n", x + o, y + o, z + o);
        }
    }
    for base in [0, 4] {
        for [a, b, c] in [[1, 3, 2], [1, 2, 4], [1, 4, 3], [2, 3, 4]] {
            obj += &format!("f {} {} {}\n", a + base, b + base, c + base);
        }
    }
    std::fs::write(dir.path().join("crossed.obj"), obj).unwrap();
    std::fs::write(
        dir.path().join("crossed.toml"),
        "[mesh]\npath = \"crossed.obj\"\ntetrahedralize = true\n[[constraints]]\ntype = \"edge_spring\"\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0]\n",
    )
    .unwrap();
    for flags in [&[][..], &["-vv"]] {
        let mut args: Vec<&str> = flags.to_vec();
        args.extend(["deform", "crossed.toml", "-o", "out.obj"]);
        let out = run_in(dir.path(), &args, &[]);
        assert_one_line_failure(&out, "crossed.toml");
        assert!(out.stderr.contains("self-intersection"), "TetGen's status, in words\n{}", out.describe());
        assert!(!out.stderr.contains("status = "), "{}", out.describe());
        assert!(!dir.path().join("out.obj").exists());
    }
}

// ---------------------------------------------------------------------------------------------
// Progress bars
// ---------------------------------------------------------------------------------------------

/// On a terminal (util-linux `script` gives the command one) `deform` draws a bar of the
/// iterations with the energy, and clears it; `-q` draws none. Piped (every other test), no bar.
#[test]
fn deform_draws_a_progress_bar_on_a_terminal_only() {
    if Command::new("script").arg("--version").output().is_err() {
        eprintln!("skipped: no `script` to give the command a terminal");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("spot.toml");
    std::fs::write(
        &scene,
        format!(
            "[mesh]\npath = '{}'\n[solver]\niterations = 150\ntolerance = 0\n[[constraints]]\ntype = \"edge_strain\"\n\
             [[constraints]]\ntype = \"position\"\nbox = {{ min = [-2, -2, -2], max = [2, 2, -0.1] }}\n\
             [[constraints]]\ntype = \"position\"\nbox = {{ min = [-2, -2, 0.8], max = [2, 2, 2] }}\ntranslate = [0, 0.2, 0.1]\n",
            data("spot.obj").display()
        ),
    )
    .unwrap();
    let on_terminal = |flags: &str| {
        let command = format!("'{}' {flags} deform spot.toml -o out.obj", env!("CARGO_BIN_EXE_shapeup"));
        let out = Command::new("script")
            .args(["-q", "-e", "-c", &command, "/dev/null"])
            .current_dir(dir.path())
            .env_remove("RUST_LOG")
            .env("TERM", "xterm")
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stdout));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let screen = on_terminal("");
    assert!(screen.contains("/150 iterations"), "a bar of the iterations: {screen:?}");
    assert!(screen.contains("E "), "with the energy: {screen:?}");
    let last = screen.rsplit('\n').find(|l| !l.trim().is_empty()).unwrap_or_default();
    assert!(last.contains("deformed 2930 vertices"), "the result line is left, not the bar: {last:?}");
    let quiet = on_terminal("-q");
    assert!(!quiet.contains("/150 iterations"), "-q: no bar: {quiet:?}");
    assert!(quiet.contains("deformed 2930 vertices"), "{quiet:?}");
}

// ---------------------------------------------------------------------------------------------
// Completions and manual pages
// ---------------------------------------------------------------------------------------------

#[test]
fn completions_cover_every_subcommand_and_bash_parses_them() {
    let dir = tempfile::tempdir().unwrap();
    let names = subcommands(dir.path());
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let script = run_in(dir.path(), &["completions", shell], &[]).success().stdout;
        for name in &names {
            assert!(script.contains(name.as_str()), "{shell}: {name} missing");
        }
        assert!(script.contains("quiet") && script.contains("verbose"), "{shell}: global flags");
    }
    let bash = run_in(dir.path(), &["completions", "bash"], &[]).success().stdout;
    let path = dir.path().join("shapeup.bash");
    std::fs::write(&path, bash).unwrap();
    if let Ok(check) = Command::new("bash").arg("-n").arg(&path).output() {
        assert!(check.status.success(), "bash -n: {}", String::from_utf8_lossy(&check.stderr));
    }
    let bad = run_in(dir.path(), &["completions", "tcsh"], &[]);
    assert_eq!(bad.code, Some(2), "{}", bad.describe());
}

#[test]
fn man_pages_cover_every_subcommand_and_render() {
    let dir = tempfile::tempdir().unwrap();
    let names = subcommands(dir.path());
    let page = run_in(dir.path(), &["man"], &[]).success().stdout;
    assert!(page.contains(".TH shapeup 1"), "{page}");
    for name in &names {
        assert!(page.contains(&format!("shapeup\\-{}", name.replace('-', "\\-"))), "{name} in SUBCOMMANDS");
    }
    assert!(page.contains("RUST_LOG"), "the environment is documented");

    let out = run_in(dir.path(), &["man", "-o", "pages"], &[]).success();
    let mut written: Vec<String> = std::fs::read_dir(dir.path().join("pages"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    written.sort();
    let mut expected: Vec<String> = names.iter().map(|n| format!("shapeup-{n}.1")).collect();
    expected.push("shapeup.1".into());
    expected.sort();
    assert_eq!(written, expected, "{}", out.describe());
    assert_eq!(std::fs::read_to_string(dir.path().join("pages/shapeup.1")).unwrap(), page);
    // groff (when there) reads every page without a warning.
    for name in &written {
        let Ok(check) = Command::new("groff")
            .args(["-k", "-man", "-Tutf8", "-ww", "-z"])
            .arg(dir.path().join("pages").join(name))
            .output()
        else {
            break;
        };
        assert!(
            check.status.success() && check.stderr.is_empty(),
            "{name}: {}",
            String::from_utf8_lossy(&check.stderr)
        );
    }

    std::fs::write(dir.path().join("a-file"), "x").unwrap();
    let out = run_in(dir.path(), &["man", "-o", "a-file"], &[]);
    assert_one_line_failure(&out, "a-file is a file, not a folder");
    // The folder is created, never the folders above it (the rule of every output).
    let out = run_in(dir.path(), &["man", "-o", "missing/man1"], &[]);
    assert_one_line_failure(&out, "the folder missing does not exist");
    assert!(!dir.path().join("missing").exists());
}

// ---------------------------------------------------------------------------------------------
// Bundled samples (from a folder that is not the repository)
// ---------------------------------------------------------------------------------------------

const SAMPLES: [&str; 6] = ["stanford-bunny", "spot", "cow", "suzanne", "beetle", "roof-quads"];

#[test]
fn samples_are_listed_and_written_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let list = run_in(dir.path(), &["samples"], &[]).success().stdout;
    for name in SAMPLES {
        let mesh = read_mesh(&data(&format!("{name}.obj"))).unwrap().mesh;
        let row = list.lines().find(|l| l.starts_with(name)).unwrap_or_else(|| panic!("{name} listed:\n{list}"));
        let numbers: Vec<usize> = row.split_whitespace().filter_map(|w| w.parse().ok()).collect();
        assert_eq!(numbers[..2], [mesh.num_vertices(), mesh.num_polygons()], "{row}");
    }
    let out = run_in(dir.path(), &["samples", "--write", "meshes"], &[]).success();
    for name in SAMPLES {
        let written = std::fs::read(dir.path().join("meshes").join(format!("{name}.obj"))).unwrap();
        assert!(written == std::fs::read(data(&format!("{name}.obj"))).unwrap(), "{name}\n{}", out.describe());
    }
    assert_eq!(std::fs::read_dir(dir.path().join("meshes")).unwrap().count(), SAMPLES.len(), "no temporary left");
    std::fs::write(dir.path().join("a-file"), "x").unwrap();
    assert_one_line_failure(
        &run_in(dir.path(), &["samples", "--write", "a-file"], &[]),
        "a-file is a file, not a folder",
    );
    assert_one_line_failure(
        &run_in(dir.path(), &["samples", "--write", "missing/meshes"], &[]),
        "missing does not exist",
    );
    assert!(!dir.path().join("missing").exists());
}

#[test]
fn a_sample_name_stands_for_a_mesh_when_no_such_file_exists() {
    let dir = tempfile::tempdir().unwrap();
    let out =
        run_in(dir.path(), &["bench", "--mesh", "cow", "--scenario", "springs", "--iterations", "1"], &[]).success();
    assert!(out.stdout.starts_with("cow.obj (bundled): 2903 vertices"), "{}", out.describe());
    assert!(out.stderr.is_empty(), "{}", out.describe());
    // A file of that name wins over the sample.
    std::fs::copy(data("spot.obj"), dir.path().join("cow")).unwrap_or_else(|e| panic!("{e}"));
    let out = run_in(dir.path(), &["info", "cow", "--json"], &[]);
    assert_one_line_failure(&out, "cow");
    assert!(!out.stderr.contains("bundled"), "the file is read, not the sample\n{}", out.describe());
    // A bare name that is no sample says so.
    assert_one_line_failure(&run_in(dir.path(), &["info", "armadillo"], &[]), "no bundled sample");
    // Names with an extension or a folder are files only.
    assert_one_line_failure(&run_in(dir.path(), &["info", "spot.obj"], &[]), "spot.obj");
}

#[test]
fn bench_without_a_mesh_uses_the_bundled_bunny_outside_the_repository() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_in(dir.path(), &["bench", "--scenario", "springs", "--iterations", "1"], &[]).success();
    assert!(out.stdout.starts_with("stanford-bunny.obj (bundled): 35947 vertices"), "{}", out.describe());
}

#[cfg(feature = "gui")]
#[test]
fn view_opens_a_sample_by_name_and_the_bunny_by_default() {
    let dir = tempfile::tempdir().unwrap();
    for args in [&["view", "suzanne"][..], &["view"]] {
        let mut args = args.to_vec();
        args.extend(["--screenshot", "shot.png", "--size", "160x120"]);
        let out = run_in(dir.path(), &args, &[]).success();
        // (Mesa may print on its own, e.g. about XDG_RUNTIME_DIR: not a log record.)
        assert!(
            !out.stderr.contains("shapeup:"),
            "the GPU's probing noise is held back on success\n{}",
            out.describe()
        );
        let png = std::fs::read(dir.path().join("shot.png")).unwrap();
        assert!(png.starts_with(b"\x89PNG"), "{args:?}");
        std::fs::remove_file(dir.path().join("shot.png")).unwrap();
    }
}

// ---------------------------------------------------------------------------------------------
// shapeup info
// ---------------------------------------------------------------------------------------------

/// Equal JSON values, numbers to 1e-12 relative (serde_json's default parser may be off by an ulp).
fn same(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= 1e-12 * x.abs().max(y.abs())
        }
        (Value::Array(x), Value::Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same(x, y)),
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

#[test]
fn info_describes_a_mesh_as_the_library_does() {
    let dir = tempfile::tempdir().unwrap();
    for (arg, file) in [("suzanne", data("suzanne.obj")), (data("cow.obj").to_str().unwrap(), data("cow.obj"))] {
        let out = run_in(dir.path(), &["info", arg, "--json"], &[]).success();
        let mut json: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
        let path = json.as_object_mut().unwrap().remove("path").unwrap();
        assert!(path.as_str().unwrap().contains(file.file_stem().unwrap().to_str().unwrap()), "{path}");
        let expected =
            serde_json::to_value(shapeup_core::inspect::MeshInfo::of_loaded(&read_mesh(&file).unwrap())).unwrap();
        assert!(same(&json, &expected), "{arg}:\n{json}\n{expected}");
        let text = run_in(dir.path(), &["info", arg], &[]).success().stdout;
        assert!(text.lines().next().unwrap().contains(file.file_stem().unwrap().to_str().unwrap()), "{text}");
        let expected = shapeup_core::inspect::MeshInfo::of_loaded(&read_mesh(&file).unwrap()).to_string();
        assert!(text.contains(expected.trim_end()), "{text}");
    }
}

#[test]
fn info_of_bad_input_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    assert_one_line_failure(&run_in(dir.path(), &["info", "broken.obj"], &[]), "broken.obj");
    std::fs::write(dir.path().join("empty.ply"), "").unwrap();
    assert_one_line_failure(&run_in(dir.path(), &["info", "empty.ply"], &[]), "empty.ply");
    std::fs::create_dir(dir.path().join("folder.obj")).unwrap();
    assert_one_line_failure(&run_in(dir.path(), &["info", "folder.obj"], &[]), "folder.obj");
}

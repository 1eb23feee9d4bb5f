//! The command-line program: help, error reporting, exit codes, time budgets and Ctrl-C.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn caustic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_caustic"))
}

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Decodes a PNG fully, failing on a truncated or corrupt file.
fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info.width, info.height)
}

#[test]
fn help_documents_every_option() {
    let out = caustic().args(["render", "--help"]).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for opt in [
        "--output",
        "--width",
        "--height",
        "--spp-axis",
        "--spp",
        "--max-depth",
        "--adc-bailout",
        "--threads",
        "--seed",
        "--integrator",
        "--sampler",
        "--time",
        "--checkpoint",
        "--quiet",
        "--no-antialias",
        "--light-samples",
        "--caustic-k",
        "--caustic-radius",
        "--volume-k",
        "--volume-radius",
        "--filter",
        "--set",
        "--display-server",
        "--spectral",
    ] {
        assert!(text.contains(opt), "render --help lacks {opt}:\n{text}");
    }
    assert!(caustic().arg("--help").output().unwrap().status.success());
}

#[test]
fn bad_scene_exits_nonzero_with_location() {
    let dir = common::scratch("cli-bad");
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"sphere\"\nradius = -2\n",
    )
    .unwrap();
    let out = caustic().arg("render").arg(&bad).arg("-o").arg(dir.join("x.png")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml:6:10") && err.contains("positive"), "{err}");
    assert!(!dir.join("x.png").exists(), "an image was written for a failed render");
}

/// An out-of-range option value is refused by name before anything is read or written.
#[test]
fn adc_bailout_outside_zero_to_one_is_refused() {
    let dir = common::scratch("cli-adc");
    for bad in ["2", "-0.1", "nan", "x"] {
        let out = caustic()
            .arg("render")
            .arg(scene("06-fresnel-glass.toml"))
            .arg(format!("--adc-bailout={bad}"))
            .arg("-o")
            .arg(dir.join("x.png"))
            .output()
            .unwrap();
        assert!(!out.status.success(), "--adc-bailout {bad} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--adc-bailout") && err.contains("from 0 to 1"), "{err}");
        assert!(!dir.join("x.png").exists());
    }
}

#[test]
fn unwritable_output_fails_before_rendering() {
    let start = Instant::now();
    let out = caustic()
        .arg("render")
        .arg(scene("06-fresnel-glass.toml"))
        .args(["--spp", "100000", "-o", "/nonexistent-dir/x.png"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(start.elapsed() < Duration::from_secs(5), "the render ran before the output was checked");
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent-dir/x.png"));
    let out = caustic().arg("render").arg(scene("06-fresnel-glass.toml")).args(["-o", "x.jpg"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png or .exr"));
}

#[test]
fn time_budget_stops_and_writes_a_valid_image() {
    let dir = common::scratch("cli-time");
    let png = dir.join("t.png");
    let start = Instant::now();
    let out = caustic()
        .arg("render")
        .arg(scene("06-fresnel-glass.toml"))
        .args(["--width", "160", "--height", "120", "--time", "2", "--quiet", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    let took = start.elapsed();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // Passes aim at 0.5 s and are cut to what the budget has left, so allow one pass beyond it
    // plus process start-up.
    assert!(took < Duration::from_millis(3500), "took {took:?}");
    assert!(took >= Duration::from_secs(2), "stopped early: {took:?}");
    assert_eq!(png_size(&png), (160, 120));
}

#[test]
fn sigint_writes_the_image_so_far_and_exits_nonzero() {
    let dir = common::scratch("cli-int");
    let png = dir.join("i.png");
    // Leave a previous image in place: it must be replaced by a complete new one, never truncated.
    std::fs::write(&png, b"old").unwrap();
    let child = caustic()
        .arg("render")
        .arg(scene("06-fresnel-glass.toml"))
        .args(["--width", "200", "--height", "150", "--spp", "1000000", "-o"])
        .arg(&png)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("interrupted") && err.contains("samples per pixel"), "{err}");
    assert_eq!(png_size(&png), (200, 150));
}

#[test]
fn photon_maps_beyond_max_memory_are_refused_before_tracing() {
    let start = Instant::now();
    let out = caustic()
        .arg("render")
        .arg(scene("13-cornell-caustics.toml"))
        .args(["--photons", "100000000", "--max-memory", "64", "-o"])
        .arg(common::scratch("cli-mem").join("m.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("MiB") && err.contains("--max-memory") && err.contains("--photons"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(5), "refusal took {:?}", start.elapsed());
}

/// A scene whose meshes would not fit is refused from the files' headers, before any is read:
/// a 30 M-triangle PLY is declared in a header of a few hundred bytes.
#[test]
fn scenes_beyond_max_memory_are_refused_before_loading() {
    let dir = common::scratch("cli-scene-mem");
    let ply = dir.join("huge.ply");
    // Only the header: the loader would fail on the missing data, the estimate never reads it.
    std::fs::write(&ply, "ply\nformat binary_little_endian 1.0\nelement vertex 15000000\nproperty float x\nproperty float y\nproperty float z\nelement face 30000000\nproperty list uchar int vertex_indices\nend_header\n").unwrap();
    let xml = dir.join("scan.xml");
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0"><shape type="ply"><string name="filename" value="huge.ply"/></shape></scene>"#,
    )
    .unwrap();
    let out = caustic()
        .arg("render")
        .arg(&xml)
        .args(["--max-memory", "1024", "-o"])
        .arg(dir.join("scan.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("loading the scene would need about") && err.contains("huge.ply") && err.contains("1024 MiB"),
        "{err}"
    );
    assert!(!dir.join("scan.png").exists());
}

/// The memory guard counts files as the loader reaches them: a scene whose first mesh fits and
/// whose second does not is refused at the second, naming it, before it is read (its data is
/// missing, which reading it would have reported instead).
#[test]
fn a_second_mesh_beyond_max_memory_is_refused_before_it_is_read() {
    let dir = common::scratch("cli-second-mesh");
    std::fs::copy(scene("mitsuba/meshes/icosphere.ply"), dir.join("ball.ply")).unwrap();
    std::fs::write(dir.join("huge.ply"), "ply\nformat binary_little_endian 1.0\nelement vertex 15000000\nproperty float x\nproperty float y\nproperty float z\nelement face 30000000\nproperty list uchar int vertex_indices\nend_header\n").unwrap();
    let toml = dir.join("two.toml");
    std::fs::write(
        &toml,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\nfile = \"ball.ply\"\n[[objects]]\ntype = \"mesh\"\nfile = \"huge.ply\"\n",
    )
    .unwrap();
    let out = caustic()
        .arg("render")
        .arg(&toml)
        .args(["--max-memory", "64", "-o"])
        .arg(dir.join("two.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("loading the scene would need about 2633 MiB")
            && err.contains("huge.ply` would add about 2633 MiB and was not read")
            && err.contains("64 MiB allowed"),
        "{err}"
    );
    assert!(!dir.join("two.png").exists());
}

#[test]
fn layers_are_written_and_sum_to_the_image() {
    let dir = common::scratch("cli-layers");
    let out = dir.join("l.exr");
    let status = caustic()
        .arg("render")
        .arg(scene("13-cornell-caustics.toml"))
        .args([
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "2",
            "--photons",
            "20000",
            "--caustic-photons",
            "20000",
            "--gather",
            "2",
            "--layers",
            "-q",
            "-o",
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let total = caustic::film::output::read_exr(&out).unwrap();
    let mut sum = vec![caustic::math::Color::ZERO; total.pixels.len()];
    for layer in caustic::film::LAYER_NAMES {
        let img = caustic::film::output::read_exr(&dir.join(format!("l.{layer}.exr"))).unwrap();
        assert!(img.mean().max_element() > 0.0, "layer {layer} is black");
        for (s, p) in sum.iter_mut().zip(&img.pixels) {
            *s += *p;
        }
    }
    for (s, t) in sum.iter().zip(&total.pixels) {
        assert!((*s - *t).abs().max_element() <= 1e-4 * (1.0 + t.max_element()), "layers sum {s} vs image {t}");
    }
}

#[test]
fn checkpoints_rewrite_the_output_during_a_render() {
    let dir = common::scratch("cli-checkpoint");
    let png = dir.join("c.png");
    let out = caustic()
        .arg("render")
        .arg(scene("06-fresnel-glass.toml"))
        .args(["--width", "160", "--height", "120", "--time", "2.5", "--checkpoint", "0.5", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.matches("checkpoint: wrote").count() >= 2, "{err}");
    assert_eq!(png_size(&png), (160, 120));
}

#[test]
fn film_and_sppm_beyond_max_memory_are_refused() {
    for args in [
        vec!["--width", "12000", "--height", "12000", "--max-memory", "256"],
        vec!["--integrator", "sppm", "--photons-per-iter", "200000000", "--max-memory", "256"],
    ] {
        let out = caustic()
            .arg("render")
            .arg(scene("11-cornell-area.toml"))
            .args(&args)
            .arg("-o")
            .arg(common::scratch("cli-mem2").join("m.png"))
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("MiB") && err.contains("--max-memory"), "{args:?}: {err}");
    }
}

/// Issue 30, item 6: `--iterations 5 --spp 9` rendered 9 without saying which won, and options
/// the integrator does not read were accepted silently. Now the conflict is an error naming both
/// and an unread option a warning naming the integrators that read it.
#[test]
fn conflicting_and_unread_options_are_said() {
    let dir = std::env::temp_dir().join(format!("caustic-cli-options-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = caustic()
        .args(["render", "--iterations", "5", "--spp", "9", "-o"])
        .arg(dir.join("a.png"))
        .arg(scene("13-cornell-caustics.toml"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--spp 9") && err.contains("--iterations 5"), "{err}");
    assert!(!dir.join("a.png").exists());
    let out = caustic()
        .args([
            "render",
            "--integrator",
            "sppm",
            "--photons",
            "1000",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "-q",
            "-o",
        ])
        .arg(dir.join("b.png"))
        .arg(scene("13-cornell-caustics.toml"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && err.contains("warning: --photons does nothing with the sppm integrator"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 30, item 2: an SPPM render stopped with Ctrl-C said `sppm: 7 iterations in 3 passes` and
/// then `took 12 iterations ... 12 spp` (the image holds 12): the driver did not count the
/// iterations an interrupted pass had finished and kept. Now the counts agree with the image.
#[test]
fn an_interrupted_sppm_render_reports_one_iteration_count() {
    let dir = common::scratch("cli-int-sppm");
    let png = dir.join("s.png");
    let child = caustic()
        .arg("render")
        .arg(scene("13-cornell-caustics.toml"))
        .args(["--integrator", "sppm", "--width", "160", "--height", "160", "--spp", "1000000", "-o"])
        .arg(&png)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).replace('\r', "\n");
    let number_before = |text: &str, word: &str| -> Option<u64> {
        let i = text.find(word)?;
        text[..i].split_whitespace().last()?.parse().ok()
    };
    let driver = err.lines().find_map(|l| l.strip_prefix("sppm: ").and_then(|r| number_before(r, " iterations in")));
    let took = err
        .lines()
        .find_map(|l| l.strip_prefix("sppm took ").and_then(|r| number_before(&format!(" {r}"), " iterations of")));
    let wrote = err.lines().find_map(|l| number_before(l, " samples per pixel"));
    assert!(driver.is_some() && driver == took && took == wrote, "{driver:?} {took:?} {wrote:?}\n{err}");
}

/// Issue 30, item 1: the summary's time left out photon-map preparation (`rendered ... in 15.24 s`
/// for a 23.7 s run). Now its total is the wall time, with the load, the photon maps and the
/// render listed.
#[test]
fn the_summary_time_is_the_whole_wall_time() {
    let dir = common::scratch("cli-wall");
    let start = Instant::now();
    let out = caustic()
        .arg("render")
        .arg(scene("13-cornell-caustics.toml"))
        .args(["--integrator", "photon", "--width", "160", "--height", "160", "--spp", "4", "-o"])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    let wall = start.elapsed().as_secs_f64();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr).replace('\r', "\n");
    let line = err.lines().find(|l| l.starts_with("rendered ")).expect("a summary line");
    let total: f64 =
        line.split(" spp in ").nth(1).and_then(|r| r.split(" s ").next()).and_then(|t| t.parse().ok()).expect(line);
    assert!(line.contains("(load ") && line.contains("photon maps ") && line.contains(", render "), "{line}");
    // The process's own start-up and exit are all that is not counted.
    assert!((total - wall).abs() <= 0.05 * wall + 0.05, "summary says {total} s, the run took {wall:.2} s: {line}");
}

/// Issue 30, item 1: `--integrator photon --time 3` ran for 4.46 s: the budget started after
/// the photon maps. It now counts from the start of the load: the run ends within a pass of the
/// budget, or of the preparation when that alone takes longer (at least one pass is rendered).
#[test]
fn the_time_budget_includes_the_photon_maps() {
    let dir = common::scratch("cli-time-photon");
    let budget: f64 = 2.0;
    let start = Instant::now();
    let out = caustic()
        .arg("render")
        .arg(scene("13-cornell-caustics.toml"))
        .args(["--integrator", "photon", "--width", "160", "--height", "160", "--time", "2", "-o"])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    let wall = start.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr).replace('\r', "\n");
    assert!(out.status.success(), "{err}");
    let line = err.lines().find(|l| l.starts_with("rendered ")).expect("a summary line");
    let seconds = |key: &str| -> f64 {
        line.split(key).nth(1).and_then(|r| r.split(" s").next()).and_then(|t| t.trim().parse().ok()).expect(line)
    };
    let before_render = seconds("(load ") + seconds("photon maps ");
    assert!(wall <= budget.max(before_render) + 1.0, "the run took {wall:.2} s for a {budget} s budget: {line}");
}

/// The screen a terminal shows after `raw` is written to it, `width` columns wide: lines, the
/// cursor moves (`ESC[nA`), line and screen clears (`ESC[nK`, `ESC[nJ`) and wrapping at the
/// last column as terminals do it (a character written there moves the cursor to the next line
/// only when another follows), which is all a progress bar uses.
#[cfg(target_os = "linux")]
fn screen(raw: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<Vec<char>> = vec![Vec::new()];
    let (mut row, mut col, mut pending) = (0usize, 0usize, false);
    let mut chars = raw.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\x1b' => {
                if chars.peek() != Some(&'[') {
                    continue;
                }
                chars.next();
                let mut arg = String::new();
                let command = loop {
                    match chars.next() {
                        Some(c) if c.is_ascii_digit() || c == ';' || c == '?' => arg.push(c),
                        Some(c) => break c,
                        None => break ' ',
                    }
                };
                let n: usize = arg.trim_start_matches('?').parse().unwrap_or(0);
                pending = false;
                match command {
                    'A' => row = row.saturating_sub(n.max(1)),
                    'K' if n == 2 => lines[row].clear(),
                    'K' => lines[row].truncate(col),
                    'J' => {
                        lines.truncate(row + 1);
                        lines[row].truncate(col);
                    }
                    _ => {}
                }
            }
            '\r' => (col, pending) = (0, false),
            '\n' => {
                (row, col, pending) = (row + 1, 0, false);
                if lines.len() <= row {
                    lines.push(Vec::new());
                }
            }
            c => {
                if pending {
                    (row, col, pending) = (row + 1, 0, false);
                    if lines.len() <= row {
                        lines.push(Vec::new());
                    }
                }
                let line = &mut lines[row];
                if line.len() <= col {
                    line.resize(col + 1, ' ');
                }
                line[col] = c;
                if col + 1 == width { pending = true } else { col += 1 }
            }
        }
    }
    lines.into_iter().map(|l| l.into_iter().collect::<String>().trim_end().to_string()).collect()
}

/// Issue 30, item 1: on a terminal the photon integrator drew a bar per phase, each clearing the
/// last (the `cache: ... 6.42 s` line was never shown), and nothing said how long the whole
/// render would take. Now one bar runs across the phases, naming each with its place in the
/// render and an ETA for all that is left, and each phase's line is printed above it and stays.
/// The program runs on a pseudo-terminal (`script`); its output is replayed as a terminal would
/// show it.
#[cfg(target_os = "linux")]
#[test]
fn on_a_terminal_phase_lines_stay_above_one_bar_with_an_eta() {
    let dir = common::scratch("cli-tty");
    let typescript = dir.join("typescript");
    let quote = |p: &Path| format!("'{}'", p.display());
    let command = format!(
        "stty cols 100 rows 50; exec {} render {} --integrator photon --width 64 --height 64 --spp 2 \
         --photons 40000 --caustic-photons 20000 -o {}",
        quote(Path::new(env!("CARGO_BIN_EXE_caustic"))),
        quote(&scene("13-cornell-caustics.toml")),
        quote(&dir.join("p.png"))
    );
    let status = Command::new("script")
        .args(["-q", "-e", "-c", &command])
        .arg(&typescript)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .status()
        .expect("script (util-linux) runs the program on a pseudo-terminal");
    assert!(status.success());
    let raw = std::fs::read_to_string(&typescript).unwrap();
    let shown = screen(&raw, 100);
    // Every phase's line is on the screen at the end, in the order the phases ran, with the
    // summary after them and no bar left.
    let at = |start: &str| shown.iter().position(|l| l.starts_with(start));
    let order: Vec<Option<usize>> =
        ["photons: ", "caustics: ", "maps: ", "gather: ", "cache: ", "render: ", "rendered "].map(at).to_vec();
    assert!(order.iter().all(Option::is_some) && order.is_sorted(), "{order:?}\n{}", shown.join("\n"));
    assert!(shown.iter().all(|l| !l.contains("ETA")), "the bar is cleared at the end:\n{}", shown.join("\n"));
    // One bar: the load, then each phase with its place among the render's seven (the load, five
    // preparation steps, the passes), and an ETA in seconds.
    assert!(raw.contains("load ["), "no bar while loading:\n{raw}");
    for (i, phase) in ["photons", "caustics", "maps", "gather", "cache", "render"].iter().enumerate() {
        assert!(raw.contains(&format!("{phase} ({}/7)", i + 2)), "no bar for {phase}:\n{raw}");
    }
    let eta = raw.split("ETA ").skip(1).any(|r| {
        r.split_whitespace().next().is_some_and(|t| t.ends_with('s') && t[..t.len() - 1].parse::<u32>().is_ok())
    });
    assert!(eta, "no ETA in seconds:\n{raw}");
}

/// An integrator that does not render participating media says so when the scene has media
/// (and renders the rest); one that does says nothing.
#[test]
fn integrators_without_media_say_they_leave_them_out() {
    let dir = common::scratch("cli-media-warning");
    let run = |integrator: &str| {
        let out = caustic()
            .arg("render")
            .arg(scene("17-volumetric-caustic.toml"))
            .args(["--integrator", integrator, "--spp", "1", "--width", "16", "--height", "12", "-o"])
            .arg(dir.join(format!("{integrator}.png")))
            .output()
            .unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let light = run("light");
    assert!(
        light.contains("the light integrator does not render participating media")
            && light.contains("rendered by: path, volpath, photon, sppm"),
        "{light}"
    );
    assert!(dir.join("light.png").exists());
    let path = run("path");
    assert!(!path.contains("participating media"), "{path}");
}

/// `--spectral` with an integrator that has no spectral mode is an error that names it, not a
/// panic (issue 31).
#[test]
fn spectral_with_an_integrator_without_it_is_an_error() {
    let dir = common::scratch("cli-spectral");
    let out = caustic()
        .args(["render", "--spectral", "--integrator", "whitted", "--width", "8", "--height", "8", "-q", "-o"])
        .arg(dir.join("x.png"))
        .arg(scene("11-cornell-area.toml"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("whitted") && err.contains("spectral") && !err.contains("panicked"), "{err}");
    let out = caustic()
        .args([
            "render",
            "--spectral",
            "--integrator",
            "path",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "1",
            "-q",
            "-o",
        ])
        .arg(dir.join("y.png"))
        .arg(scene("11-cornell-area.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

//! Render farm (issue 14): shards merged are the one-machine render bit for bit, merge refuses
//! what does not make one render, a shard stopped by SIGTERM resumes, and the generated Slurm
//! scripts quote every path and argument.

mod common;

use caustic::app::{AppError, RenderOptions, merge_files, render_file};
use caustic::farm::shard::{Shard, ShardSpec};
use caustic::film::output::read_exr;
use caustic::options::{IntegratorKind, Options, PhotonOptions};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

static NEVER: AtomicBool = AtomicBool::new(false);

fn cornell() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/13-cornell-caustics.toml")
}

fn options(scene: &Path, kind: IntegratorKind, spp: u32, output: PathBuf, shard: Option<Shard>) -> RenderOptions {
    RenderOptions {
        scene: scene.to_path_buf(),
        output: Some(output),
        overrides: Options {
            width: Some(24),
            height: Some(20),
            spp: Some(spp),
            integrator: Some(kind),
            photon: PhotonOptions {
                photons: Some(4000),
                caustic_photons: Some(2000),
                photons_per_iter: Some(2000),
                ..Default::default()
            },
            ..Default::default()
        },
        threads: Some(2),
        quiet: true,
        shard: shard.map(ShardSpec::Fixed),
        ..Default::default()
    }
}

/// The bits of an EXR's RGB pixels.
fn bits(path: &Path) -> Vec<[u32; 3]> {
    read_exr(path).unwrap().pixels.iter().map(|c| c.to_array().map(f32::to_bits)).collect()
}

/// Renders the `count` shards of a render to `dir` and returns their paths.
fn shards(scene: &Path, kind: IntegratorKind, spp: u32, count: u32, dir: &Path) -> Vec<PathBuf> {
    (0..count)
        .map(|index| {
            let part = dir.join(format!("{}-{spp}-{index}of{count}.exr", kind.name()));
            render_file(&options(scene, kind, spp, part.clone(), Some(Shard { index, count })), &NEVER).unwrap();
            part
        })
        .collect()
}

#[test]
fn merged_shards_are_the_single_render_bit_for_bit() {
    let dir = common::scratch("farm-exact");
    let scene = cornell();
    for kind in [
        IntegratorKind::Whitted,
        IntegratorKind::Path,
        IntegratorKind::Photon,
        IntegratorKind::Light,
        IntegratorKind::Bdpt,
    ] {
        // 5 samples over 7 shards leaves two shards empty; 16 over 3 and 7 split unevenly.
        for spp in [5, 16] {
            let single = dir.join(format!("{}-{spp}.exr", kind.name()));
            render_file(&options(&scene, kind, spp, single.clone(), None), &NEVER).unwrap();
            let expected = bits(&single);
            for count in [1, 2, 3, 7] {
                let parts = shards(&scene, kind, spp, count, &dir);
                let merged = dir.join(format!("{}-{spp}-merged{count}.exr", kind.name()));
                let report = merge_files(&parts, &merged, false, true).unwrap();
                assert_eq!((report.min_samples, report.max_samples), (spp, spp));
                assert!(bits(&merged) == expected, "{} at {spp} spp in {count} shards differs", kind.name());
                // The parts in any order give the same image.
                let mut reversed = parts.clone();
                reversed.reverse();
                merge_files(&reversed, &merged, false, true).unwrap();
                assert!(bits(&merged) == expected);
            }
        }
    }
}

/// Filters with negative lobes weight samples by -1 or +1 (times a constant) and a crop renders a
/// window of the film: the sums stay exact, so shards still merge into the one-machine image.
#[test]
fn merged_shards_of_a_filtered_crop_are_the_single_render_bit_for_bit() {
    let dir = common::scratch("farm-filter");
    let scene = dir.join("filtered.toml");
    let text = std::fs::read_to_string(cornell()).unwrap().replacen(
        "[render]",
        "[render]\nfilter = { type = \"lanczos\", lobes = 2 }\ncrop = { x = 40, y = 30, width = 300, height = 250 }",
        1,
    );
    std::fs::write(&scene, text).unwrap();
    let kind = IntegratorKind::Path;
    let single = dir.join("single.exr");
    render_file(&options(&scene, kind, 7, single.clone(), None), &NEVER).unwrap();
    let expected = bits(&single);
    let img = read_exr(&single).unwrap();
    assert!(img.width < 24 && img.height < 20, "the crop was not applied: {} x {}", img.width, img.height);
    let parts = shards(&scene, kind, 7, 3, &dir);
    let merged = dir.join("merged.exr");
    merge_files(&parts, &merged, false, true).unwrap();
    assert!(bits(&merged) == expected, "merged shards of a Lanczos-filtered crop differ");
}

#[test]
fn merged_layers_are_the_single_renders_layers() {
    let dir = common::scratch("farm-layers");
    let scene = cornell();
    let with_layers = |mut o: RenderOptions| {
        o.layers = true;
        o
    };
    let single = dir.join("one.exr");
    render_file(&with_layers(options(&scene, IntegratorKind::Path, 6, single.clone(), None)), &NEVER).unwrap();
    let parts: Vec<PathBuf> = (0..3)
        .map(|index| {
            let p = dir.join(format!("p{index}.exr"));
            let o = options(&scene, IntegratorKind::Path, 6, p.clone(), Some(Shard { index, count: 3 }));
            render_file(&with_layers(o), &NEVER).unwrap();
            p
        })
        .collect();
    let merged = dir.join("m.exr");
    merge_files(&parts, &merged, false, true).unwrap();
    assert!(bits(&merged) == bits(&single));
    for layer in caustic::film::LAYER_NAMES {
        let name = |p: &Path| caustic::film::output::layer_path(p, layer);
        assert!(bits(&name(&merged)) == bits(&name(&single)), "layer {layer} differs");
    }
}

#[test]
fn sppm_shards_are_independent_runs_weighted_by_iterations() {
    let dir = common::scratch("farm-sppm");
    let scene = cornell();
    let kind = IntegratorKind::Sppm;
    // One shard is the plain render.
    let single = dir.join("one.exr");
    render_file(&options(&scene, kind, 6, single.clone(), None), &NEVER).unwrap();
    let one = shards(&scene, kind, 6, 1, &dir);
    let merged = dir.join("m1.exr");
    merge_files(&one, &merged, false, true).unwrap();
    assert!(bits(&merged) == bits(&single));
    // Shards of 2 and 4 iterations: the merge is their mean weighted 2:4.
    let parts = shards(&scene, kind, 6, 3, &dir);
    let parts = vec![parts[0].clone(), parts[1].clone(), parts[2].clone()];
    let merged = dir.join("m3.exr");
    let report = merge_files(&parts, &merged, false, true).unwrap();
    assert_eq!(report.total, 6);
    let img: Vec<_> = parts.iter().map(|p| read_exr(p).unwrap()).collect();
    let m = read_exr(&merged).unwrap();
    for k in 0..m.pixels.len() {
        let expect = (img[0].pixels[k] * 2.0 + img[1].pixels[k] * 2.0 + img[2].pixels[k] * 2.0) / 6.0;
        assert!((m.pixels[k] - expect).abs().max_element() <= 1e-5 * (1.0 + expect.max_element()), "pixel {k}");
    }
    // The three runs are distinct (their own photons and radii), so the merge is not any one.
    assert_ne!(img[0], img[1]);
}

/// The message of a merge that must fail.
fn refusal(parts: &[PathBuf], out: &Path) -> String {
    match merge_files(parts, out, false, true) {
        Ok(r) => panic!("merge of {parts:?} should have been refused, got {r:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn merge_refuses_parts_that_do_not_make_one_render() {
    let dir = common::scratch("farm-refuse");
    let scene = dir.join("scene.toml");
    std::fs::copy(cornell(), &scene).unwrap();
    let kind = IntegratorKind::Path;
    let part = |name: &str, o: RenderOptions| {
        render_file(&o, &NEVER).unwrap();
        let _ = name;
        o.output.unwrap()
    };
    let shard = |i, n| Some(Shard { index: i, count: n });
    let p0 = part("p0", options(&scene, kind, 8, dir.join("p0.exr"), shard(0, 2)));
    let p1 = part("p1", options(&scene, kind, 8, dir.join("p1.exr"), shard(1, 2)));
    let out = dir.join("out.exr");
    merge_files(&[p0.clone(), p1.clone()], &out, false, true).unwrap();

    // Another seed.
    let mut o = options(&scene, kind, 8, dir.join("seed.exr"), shard(1, 2));
    o.overrides.seed = Some(99);
    let e = refusal(&[p0.clone(), part("seed", o)], &out);
    assert!(e.contains("different renders") && e.contains("`seed` is 0") && e.contains("99"), "{e}");
    // Another option that changes the image.
    let mut o = options(&scene, kind, 8, dir.join("depth.exr"), shard(1, 2));
    o.overrides.max_depth = Some(2);
    let e = refusal(&[p0.clone(), part("depth", o)], &out);
    assert!(e.contains("`max_depth`"), "{e}");
    let mut o = options(&scene, kind, 8, dir.join("adc.exr"), shard(1, 2));
    o.overrides.adc_bailout = Some(0.0);
    let e = refusal(&[p0.clone(), part("adc", o)], &out);
    assert!(e.contains("`adc_bailout`"), "{e}");
    // Another integrator, another sample count.
    let e = refusal(
        &[p0.clone(), part("w", options(&scene, IntegratorKind::Whitted, 8, dir.join("w.exr"), shard(1, 2)))],
        &out,
    );
    assert!(e.contains("`integrator`"), "{e}");
    let e = refusal(&[p0.clone(), part("n", options(&scene, kind, 9, dir.join("n.exr"), shard(1, 2)))], &out);
    assert!(e.contains("`samples` is 8"), "{e}");
    // The scene file changed between shards.
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("fov = 39.3", "fov = 40")).unwrap();
    let changed = part("changed", options(&scene, kind, 8, dir.join("changed.exr"), shard(1, 2)));
    std::fs::write(&scene, &text).unwrap();
    let e = refusal(&[p0.clone(), changed], &out);
    assert!(e.contains("`scene`"), "{e}");
    // Overlaps: the same part twice, and shards of different splits.
    let e = refusal(&[p0.clone(), p1.clone(), p0.clone()], &out);
    assert!(e.contains("given twice") && e.contains("0..4"), "{e}");
    let third = part("third", options(&scene, kind, 8, dir.join("third.exr"), shard(1, 3)));
    let e = refusal(&[p0.clone(), third.clone()], &out);
    assert!(e.contains("overlap") && e.contains("samples 2..4"), "{e}");
    // A gap: shard 1 of 2 missing, named by its samples; allowed on request.
    let e = refusal(std::slice::from_ref(&p0), &out);
    assert!(e.contains("missing samples 4..8") && e.contains("--allow-partial"), "{e}");
    let e = refusal(std::slice::from_ref(&p1), &out);
    assert!(e.contains("samples 0..4 (no part holds them)"), "{e}");
    let r = merge_files(std::slice::from_ref(&p0), &out, true, true).unwrap();
    assert_eq!((r.min_samples, r.total), (4, 8));
    assert_eq!(read_exr(&out).unwrap(), read_exr(&p0).unwrap());
    // Truncated and damaged files, and files that are not parts, are named and never read.
    let bytes = std::fs::read(&p1).unwrap();
    let cut = dir.join("cut.exr");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let e = refusal(&[p0.clone(), cut], &out);
    assert!(e.contains("cut.exr"), "{e}");
    let plain = dir.join("plain.exr");
    render_file(&options(&scene, kind, 8, plain.clone(), None), &NEVER).unwrap();
    let e = refusal(&[p0.clone(), plain], &out);
    assert!(e.contains("plain.exr") && e.contains("not a caustic partial image"), "{e}");
    let e = refusal(&[p0.clone(), dir.join("nowhere.exr")], &out);
    assert!(e.contains("nowhere.exr") && e.contains("does not exist"), "{e}");
}

#[test]
fn shard_options_are_checked_before_rendering() {
    let dir = common::scratch("farm-options");
    let scene = cornell();
    let e = render_file(
        &options(&scene, IntegratorKind::Path, 4, dir.join("p.png"), Some(Shard { index: 0, count: 2 })),
        &NEVER,
    )
    .err()
    .unwrap();
    assert!(matches!(e, AppError::Shard(_)) && e.to_string().contains(".exr"), "{e}");
    let mut o = options(&scene, IntegratorKind::Path, 4, dir.join("p.exr"), Some(Shard { index: 0, count: 2 }));
    o.time_limit = Some(std::time::Duration::from_secs(5));
    assert!(render_file(&o, &NEVER).err().unwrap().to_string().contains("--time"));
    // `auto` without a scheduler's variable says which variables it reads.
    let mut o = options(&scene, IntegratorKind::Path, 4, dir.join("p.exr"), None);
    o.shard = Some(ShardSpec::Auto { count: 2 });
    if caustic::farm::shard::INDEX_VARIABLES.iter().all(|v| std::env::var_os(v).is_none()) {
        let e = render_file(&o, &NEVER).err().unwrap().to_string();
        assert!(e.contains("SLURM_ARRAY_TASK_ID") && e.contains("JOB_COMPLETION_INDEX"), "{e}");
    }
}

/// A shard that receives SIGTERM part-way saves the samples it finished and exits with 143; run
/// again with the same arguments it resumes, and the merge is still the single render bit for bit.
#[test]
fn a_shard_stopped_by_sigterm_resumes_and_merges_bit_for_bit() {
    use std::process::{Command, Stdio};
    let dir = common::scratch("farm-sigterm");
    let scene = cornell();
    let exe = env!("CARGO_BIN_EXE_caustic");
    let args = |shard: &str, out: &Path| {
        let mut a: Vec<String> = ["render", scene.to_str().unwrap(), "--integrator", "path", "--width", "96"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        a.extend(
            ["--height", "96", "--spp", "240", "--threads", "2", "--checkpoint", "0.2", "--quiet"].map(String::from),
        );
        a.extend(["--shard".to_string(), shard.to_string(), "-o".to_string(), out.display().to_string()]);
        a
    };
    let p1 = dir.join("p1.exr");
    let mut child = Command::new(exe).args(args("1/2", &p1)).stderr(Stdio::piped()).spawn().unwrap();
    // Stop it once a checkpoint shows it under way.
    let start = std::time::Instant::now();
    while !p1.exists() && start.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap().success());
    let status = child.wait().unwrap();
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(143), "{stderr}");
    assert!(stderr.contains("SIGTERM") && stderr.contains("resume"), "{stderr}");
    let partial = caustic::farm::partial::read_partial(&p1).unwrap();
    let held = partial.film.min_samples();
    assert!(held < 120, "the shard finished before SIGTERM arrived ({held} samples): the test proves nothing");
    // The merge names what is missing.
    let p0 = dir.join("p0.exr");
    let run = |shard: &str, out: &Path| {
        let o = Command::new(exe).args(args(shard, out)).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run("0/2", &p0);
    let e = refusal(&[p0.clone(), p1.clone()], &dir.join("m.exr"));
    assert!(e.contains("p1.exr") && e.contains("stopped early"), "{e}");
    // Resumed, it finishes; the merge equals the single render.
    run("1/2", &p1);
    let merged = dir.join("m.exr");
    merge_files(&[p0, p1], &merged, false, true).unwrap();
    let single = dir.join("single.exr");
    let mut a = args("0/1", &single);
    let at = a.iter().position(|s| s == "--shard").unwrap();
    a.drain(at..at + 2);
    let o = Command::new(exe).args(&a).output().unwrap();
    assert!(o.status.success());
    assert!(bits(&merged) == bits(&single), "the resumed shard changed the image");
}

/// Every path and argument reaches the program intact through the generated scripts, however
/// many quotes, spaces, dollars and other shell metacharacters it holds.
#[test]
fn generated_scripts_quote_every_path_and_argument() {
    use caustic::farm::slurm::{FarmPlan, write_scripts};
    use std::process::Command;
    let root = common::scratch("farm-quoting");
    let dir = root.join("it's a \"dir\" with $HOME; & | * `x` %a");
    std::fs::create_dir_all(&dir).unwrap();
    // A stand-in for caustic and one for sbatch: each prints its arguments, NUL-separated.
    let bin = root.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let print_args = "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\0' \"$a\"; done\n";
    let exe = dir.join("fake caustic");
    std::fs::write(&exe, print_args).unwrap();
    let record = root.join("sbatch-calls");
    let sbatch = format!(
        "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\0' \"$a\"; done >> '{}'\nprintf '\\n' >> '{}'\necho 4242\n",
        record.display(),
        record.display()
    );
    std::fs::write(bin.join("sbatch"), sbatch).unwrap();
    for f in [&exe, &bin.join("sbatch")] {
        Command::new("chmod").arg("+x").arg(f).status().unwrap();
    }
    let tricky = "a b'c\"$x`y`\\z;\nnext line";
    let plan = FarmPlan {
        exe: exe.clone(),
        scene: dir.join("my scene's.toml"),
        output: dir.join("out put.exr"),
        shards: 3,
        render_args: vec![format!("-Dname={tricky}"), "--spp=4".into()],
        partition: Some("main".into()),
        time_limit: Some("1:00:00".into()),
        sbatch_args: vec!["--comment=two words 'and' $more".into()],
    };
    let files = write_scripts(&plan).unwrap();
    let args_of = |out: std::process::Output| -> Vec<String> {
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let s = String::from_utf8(out.stdout).unwrap();
        s.split('\0').filter(|a| !a.is_empty()).map(String::from).collect()
    };
    let shard = args_of(Command::new("sh").arg(&files.array_script).env("SLURM_ARRAY_TASK_ID", "2").output().unwrap());
    let part2 = files.parts[2].display().to_string();
    let scene = plan.scene.display().to_string();
    let expected = ["render", &scene, "--shard", "auto/3", &format!("-Dname={tricky}"), "--spp=4", "-o", &part2];
    assert_eq!(shard, expected);
    let merge = args_of(Command::new("sh").arg(&files.merge_script).output().unwrap());
    let mut expected: Vec<String> = vec!["merge".into()];
    expected.extend(files.parts.iter().map(|p| p.display().to_string()));
    expected.extend(["-o".into(), plan.output.display().to_string()]);
    assert_eq!(merge, expected);
    // submit.sh passes the same sbatch arguments `farm slurm` uses, with the array's id in the
    // merge job's dependency.
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let out = Command::new("sh").arg(&files.submit_script).env("PATH", path).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("array job 4242 (3 shards) and merge job 4242"));
    let calls = std::fs::read_to_string(&record).unwrap();
    let calls: Vec<Vec<String>> = calls
        .split('\n')
        .filter(|c| !c.is_empty())
        .map(|c| c.split('\0').filter(|a| !a.is_empty()).map(String::from).collect())
        .collect();
    let mut array = vec!["--parsable".to_string()];
    array.extend(files.array_sbatch.iter().cloned());
    let mut merge = vec!["--parsable".to_string(), "--dependency=afterok:4242".to_string()];
    merge.extend(files.merge_sbatch.iter().cloned());
    assert_eq!(calls, vec![array.clone(), merge]);
    // The log file pattern keeps the folder's literal `%` (Slurm reads `%%` as one).
    assert!(
        array.iter().any(|a| a.starts_with("--output=") && a.contains("%%a/") && a.ends_with("shard-%a.log")),
        "{array:?}"
    );
    assert!(array.contains(&"--requeue".to_string()) && array.contains(&"--array=0-2".to_string()));
}

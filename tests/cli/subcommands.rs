//! `converge`, `info`, `reference` and `merge`.

use super::{caustica, path_str, render_ok, run, stderr, temp_dir};
use caustica_renderer::image::read_exr;
use std::path::PathBuf;

/// `converge` with a reference and a swept parameter: the CSV has a row per checkpoint of every
/// run with true and estimated error, the PNG is an image, and stdout names the winners and
/// the slopes.
#[test]
fn converge_measures_every_run_against_the_reference() {
    let dir = temp_dir("converge");
    let reference = dir.join("ref.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &reference,
        "--width 32 --spp 1024 --seed 77",
    );
    let out = dir.join("measured");
    let converge = format!(
        "converge assets/cornell-box.gltf --reference {} --out {}",
        reference.display(),
        out.display()
    );
    let o = run(&format!(
        "{converge} --integrator pt,sppm --param photons=2000,8000 --time 1.5"
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    for run in ["pt", "sppm photons=2000", "sppm photons=8000"] {
        assert!(stdout.contains(run), "{stdout}");
    }
    assert!(stdout.contains("lowest relMSE"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header.join(" "),
        "run integrator parameters seconds passes rel_mse rmse estimated_rel_mse \
         estimated_bias_rel_mse seed"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    for run in ["pt", "sppm photons=2000", "sppm photons=8000"] {
        let mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == run).collect();
        assert!(mine.len() >= 3, "{run}: {csv}");
        let errors: Vec<f64> = mine.iter().map(|r| r[5].parse().unwrap()).collect();
        assert!(
            errors.last().unwrap() < errors.first().unwrap(),
            "{run}: the error falls: {errors:?}"
        );
        // Every frame of two passes or more estimates its error (one pass cannot).
        assert!(
            mine.iter()
                .filter(|r| r[4].parse::<u64>().unwrap() >= 2)
                .all(|r| r[7].parse::<f64>().unwrap() > 0.0),
            "{csv}"
        );
    }
    let png = image::open(out.join("convergence.png")).unwrap();
    assert!(png.width() > 400 && png.height() > 300);
    // Several seeds: every seed's rows, the median and the seeds' range in the table.
    let o = run(&format!(
        "{converge} --integrator pt --time 0.5 --seeds 2 --seed 7"
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("seeds' range"));
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    for seed in ["7", "8"] {
        assert!(
            csv.lines()
                .skip(1)
                .any(|l| l.ends_with(&format!(",{seed}"))),
            "{csv}"
        );
    }
    // A reference of another size is refused before anything renders.
    let o = run(&format!("{converge} --integrator pt --time 1 --width 40"));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("ref.exr"), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

/// `info` describes the transport and recommends what the bundled scenes need; `reference`
/// renders with it and writes its estimated error.
#[test]
fn info_recommends_and_reference_renders_with_the_recommendation() {
    for (scene, expected, reference) in [
        ("assets/cornell-box.gltf", "pt", "pt"),
        ("assets/caustic-pool.gltf", "sppm", "sppm"),
        ("assets/door.gltf", "amcppm", "bdpt"),
        ("assets/gap-glass.gltf", "amcppm", "bdpt"),
    ] {
        let o = run(&format!("info {scene} --width 64"));
        assert!(o.status.success(), "{}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            stdout.contains(&format!("recommended: {expected}\n")),
            "{scene}: {stdout}"
        );
        assert!(
            stdout.contains(&format!("--integrator {expected}")),
            "{stdout}"
        );
        assert!(
            stdout.contains(&format!("renders with {reference}\n")),
            "{stdout}"
        );
    }
    let dir = temp_dir("reference");
    let out = dir.join("pool.exr");
    let o = run(&format!(
        "reference assets/caustic-pool.gltf -o {} --time 1 --width 32",
        out.display()
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, meta) = read_exr(&out).unwrap();
    assert_eq!(meta["integrator"], "sppm");
    assert!(meta["estimated_relmse"].parse::<f64>().unwrap() > 0.0);
    let o = run(&format!(
        "reference assets/caustic-pool.gltf -o {} --time 1 --width 32 --integrator bdpt",
        out.display()
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(read_exr(&out).unwrap().1["integrator"], "bdpt");
    let o = run("reference assets/door.gltf -o x.png --time 1");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

/// Merging k independent runs gives what one run k times as long gives: against a long
/// reference their errors agree within the statistics (both are means of the same number of
/// independent passes; at 32 x 32 the relative spread of relMSE is about 10 %, so we allow
/// 30 %), while averaging the runs unweighted (passes 2, 4, 6, 12) or summing them would not.
/// The header adds up the passes and carries the merged error estimate.
#[test]
fn merging_runs_equals_one_longer_run() {
    let dir = temp_dir("merge");
    let render_box = |name: &str, spp: u32, seed: u32| {
        let path = dir.join(name);
        render_ok(
            "assets/cornell-box.gltf",
            &path,
            &format!("--width 32 --spp {spp} --seed {seed}"),
        );
        path
    };
    let reference = render_box("ref.exr", 4096, 1000);
    let long = render_box("long.exr", 24, 50);
    let parts: Vec<PathBuf> = [(2, 1), (4, 2), (6, 3), (12, 4)]
        .iter()
        .map(|(spp, seed)| render_box(&format!("part{seed}.exr"), *spp, *seed))
        .collect();
    let merged_path = dir.join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| path_str(p)));
    args.extend(["-o", path_str(&merged_path)]);
    let o = caustica(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let (reference, _) = read_exr(&reference).unwrap();
    let (long, long_meta) = read_exr(&long).unwrap();
    let (merged, meta) = read_exr(&merged_path).unwrap();
    assert_eq!(meta["passes"], "24");
    assert_eq!(meta["seed"], "1,2,3,4");
    let error = |img| {
        caustica_renderer::image::compare(img, &reference)
            .unwrap()
            .rel_mse
    };
    let (e_long, e_merged) = (error(&long), error(&merged));
    eprintln!("relMSE: one run of 24 passes {e_long:.4e}, four merged {e_merged:.4e}");
    assert!(
        (e_merged / e_long - 1.0).abs() < 0.3,
        "{e_merged} vs {e_long}"
    );
    let estimated: f64 = meta["estimated_relmse"].parse().unwrap();
    let long_estimated: f64 = long_meta["estimated_relmse"].parse().unwrap();
    assert!(
        (estimated / long_estimated - 1.0).abs() < 0.3,
        "{estimated} vs {long_estimated}"
    );
    // Two runs with one seed are the same samples: refused.
    let o = caustica(&[
        "merge",
        path_str(&parts[0]),
        path_str(&parts[0]),
        "-o",
        path_str(&merged_path),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

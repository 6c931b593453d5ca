//! The gallery and `wgtrace validate`: every scene has a gallery image, every image is
//! committed at its scene's size, the README's gallery table lists them all, the table is
//! rewritten only between its markers, and the gallery tool (examples/gallery, a
//! development tool) and `wgtrace validate` behave as a user runs them.

mod common;

#[path = "../examples/gallery/entries.rs"]
#[allow(dead_code)]
mod entries;
#[path = "../examples/gallery/readme.rs"]
#[allow(dead_code)]
mod readme;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use entries::ENTRIES;
use readme::{replace_block, README_END, README_START};
use wgtrace::report::civil_date;

fn wgtrace(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wgtrace"))
        .args(args)
        .current_dir(common::repo_path("."))
        .output()
        .expect("run wgtrace")
}

#[test]
fn every_scene_has_a_committed_gallery_image_listed_in_the_readme() {
    let shown: BTreeSet<&str> = ENTRIES.iter().map(|e| e.scene).collect();
    for path in common::scene_files() {
        let rel = format!("scenes/{}", path.file_name().unwrap().to_string_lossy());
        assert!(shown.contains(rel.as_str()), "{rel} is not in the gallery");
    }
    let names: BTreeSet<&str> = ENTRIES.iter().map(|e| e.name).collect();
    assert_eq!(
        names.len(),
        ENTRIES.len(),
        "two gallery images share a name"
    );
    let readme = std::fs::read_to_string(common::repo_path("README.md")).unwrap();
    let start = readme
        .find(README_START)
        .expect("the README's gallery start line");
    let end = readme
        .find(README_END)
        .expect("the README's gallery end line");
    let table = &readme[start..end];
    for e in ENTRIES {
        let scene = wgtrace::load_scene(&common::repo_path(e.scene), &Default::default());
        let image = format!("docs/gallery/{}.png", e.name);
        let png = image::open(common::repo_path(&image)).unwrap_or_else(|err| {
            panic!("{image}: {err} (run `cargo run --release --example gallery`)")
        });
        if let Ok(scene) = scene {
            assert_eq!(
                (png.width(), png.height()),
                (scene.width, scene.height),
                "{image} is not at {}'s size",
                e.scene
            );
        }
        assert!(
            table.contains(&format!("src=\"{image}\""))
                && table.contains(&format!("({})", e.scene)),
            "the README's gallery table lacks {image} or {}",
            e.scene
        );
    }
}

#[test]
fn the_gallery_block_is_replaced_between_its_markers_only() {
    let readme = format!("# t\n\nbefore\n{README_START}\nold table\n{README_END}\nafter\n");
    let new = replace_block(&readme, &format!("{README_START}\nnew\n{README_END}")).unwrap();
    assert_eq!(
        new,
        format!("# t\n\nbefore\n{README_START}\nnew\n{README_END}\nafter\n")
    );
    assert!(replace_block("no markers", "x").is_err());
    assert!(replace_block(&format!("{README_END}\n{README_START}\n"), "x").is_err());
}

/// The gallery tool, built in this test's profile (a `cargo build` that finds it up to
/// date when `cargo test` has built the examples).
fn gallery_tool(args: &[&str]) -> std::process::Output {
    let exe = std::env::current_exe().unwrap();
    let profile = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/PROFILE/deps");
    let mut build = Command::new(env!("CARGO"));
    build.args(["build", "--quiet", "--example", "gallery"]);
    if profile.file_name().is_some_and(|n| n == "release") {
        build.arg("--release");
    }
    let status = build
        .current_dir(common::repo_path("."))
        .status()
        .expect("run cargo");
    assert!(status.success(), "cargo build --example gallery failed");
    let tool: PathBuf = profile.join("examples").join("gallery");
    Command::new(tool)
        .args(args)
        .current_dir(common::repo_path("."))
        .output()
        .expect("run the gallery tool")
}

#[test]
fn the_gallery_dates_its_table_by_the_calendar() {
    assert_eq!(civil_date(0), "1970-01-01");
    assert_eq!(civil_date(11_016), "2000-02-29");
    assert_eq!(civil_date(20_789), "2026-12-02");
    assert_eq!(civil_date(-1), "1969-12-31");
}

#[test]
fn gallery_renders_the_chosen_images_leaves_the_readme_alone_and_checks_it_first() {
    let dir = common::tmp_dir("gallery-only");
    let out = dir.display().to_string();
    let o = gallery_tool(&["--only", "plane", "--spp", "1", "--out", &out]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("left alone"), "{stdout}");
    let png = image::open(dir.join("plane.png")).expect("plane.png");
    assert_eq!((png.width(), png.height()), (320, 240));
    let o = gallery_tool(&["--only", "nope", "--out", &out]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("nope") && stderr.contains("showcase"),
        "{stderr}"
    );
    // a full run checks the README's markers before it renders anything
    let readme = dir.join("README.md");
    std::fs::write(&readme, "# no gallery here\n").unwrap();
    let full_out = dir.join("full");
    let o = gallery_tool(&[
        "--readme",
        &readme.display().to_string(),
        "--out",
        &full_out.display().to_string(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(stderr.contains(README_START), "{stderr}");
    assert!(
        !full_out.exists(),
        "images were rendered before the README was checked"
    );
}

#[test]
fn validate_checks_scenes_without_rendering_and_names_the_problem() {
    let o = wgtrace(&["validate", "scenes/cornell.toml", "scenes/materials.toml"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("scenes/cornell.toml: ok: 256 x 256, 64 spp")
            && stdout.contains("scenes/materials.toml: ok"),
        "{stdout}"
    );
    let dir = common::tmp_dir("validate-bad");
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\n\
         m = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n[[objects]]\n\
         type = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\nmaterial = \"m\"\n",
    )
    .unwrap();
    let bad_s = bad.display().to_string();
    let o = wgtrace(&["validate", "scenes/cornell.toml", &bad_s]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "a bad scene passed");
    assert!(
        stderr.contains(&format!("{bad_s}:6:1: objects[0].radius")),
        "{stderr}"
    );
    assert!(stderr.contains("1 of 2 scenes"), "{stderr}");
    assert!(!Path::new(&dir.join("bad.png")).exists());
}

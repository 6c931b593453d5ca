//! The Mitsuba importer against Mitsuba 3 itself: each scene of tests/mitsuba/*.xml, read
//! by wgtrace as a user would (`wgtrace render scene.xml`), rendered on the CPU reference
//! and judged pixel by pixel against the image Mitsuba 3.9.1 rendered from the same file
//! (tests/mitsuba/refs, written by bench/mitsuba_refs.py: the mean of its runs and that
//! mean's standard error), as Mitsuba's own render tests judge: each pixel and channel's
//! difference over both standard errors, the Sidak bound at significance 0.01 over all of
//! them, and at least 99.75% within it. Also `wgtrace convert` and the importer's errors.

mod common;

use std::path::{Path, PathBuf};

use wgtrace::scene::mesh::write_serialized;
use wgtrace::Overrides;

/// A w x h RGB image whose texel at (u, v) (its centre, from the top left, in [0, 1]) is
/// `f(u, v)`.
fn image(w: usize, h: usize, f: impl Fn(f64, f64) -> [f64; 3]) -> Vec<f32> {
    let mut img = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let rgb = f((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64);
            img.extend(rgb.map(|c| c as f32));
        }
    }
    img
}

/// The environment image of environment.xml, as bench/mitsuba_assets.py writes it: 128 x
/// 64, a vertical gradient and a bright spot.
fn sky() -> Vec<f32> {
    image(128, 64, |u, v| {
        let spot = (-((u - 0.3).powi(2) + (v - 0.3).powi(2)) / 0.005).exp();
        [
            0.1 + 0.5 * (1.0 - v) + 0.35 * spot,
            0.1 + 0.45 * (1.0 - v) + 0.3 * spot,
            0.15 + 0.6 * (1.0 - v) + 0.2 * spot,
        ]
    })
}

/// The environment image of envmap-texels.xml, as bench/mitsuba_assets.py writes it: 16 x 8
/// texels, checkered 1 and 0.1 times a colour that changes along each row and down each
/// column.
fn texels() -> Vec<f32> {
    image(16, 8, |u, v| {
        let (i, j) = ((u * 16.0) as u32, (v * 8.0) as u32);
        let k = if (i + j) % 2 == 0 { 1.0 } else { 0.1 };
        [k * (0.5 + i as f64 / 30.0), k * (0.5 + j as f64 / 14.0), k]
    })
}

/// The normal map of normalmap.xml, as bench/mitsuba_assets.py writes it: the normals of a
/// height 0.015 sin(2 pi 3 u) sin(2 pi 2 v) as colours (n + 1) / 2.
fn waves() -> Vec<f32> {
    use std::f64::consts::PI;
    image(64, 64, |u, v| {
        let du = 0.015 * 2.0 * PI * 3.0 * (2.0 * PI * 3.0 * u).cos() * (2.0 * PI * 2.0 * v).sin();
        let dv = 0.015 * 2.0 * PI * 2.0 * (2.0 * PI * 3.0 * u).sin() * (2.0 * PI * 2.0 * v).cos();
        let len = (du * du + dv * dv + 1.0).sqrt();
        [-du / len, -dv / len, 1.0 / len].map(|c| (c + 1.0) / 2.0)
    })
}

/// The .serialized file of shapes.xml: a decoy triangle, then a square pyramid.
fn pyramid() -> Vec<u8> {
    write_serialized(&[
        (
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
            vec![],
        ),
        (
            vec![
                [-0.4, 0.0, -0.4],
                [0.4, 0.0, -0.4],
                [0.4, 0.0, 0.4],
                [-0.4, 0.0, 0.4],
                [0.0, 0.9, 0.0],
            ],
            vec![
                [0, 1, 2],
                [0, 2, 3],
                [0, 4, 1],
                [1, 4, 2],
                [2, 4, 3],
                [3, 4, 0],
            ],
            vec![],
        ),
    ])
}

/// The .serialized quads of mesh-uvs.xml (as bench/mitsuba_assets.py writes them), [-1, 1]^2
/// at z = 0: one without uvs wound toward -z, one with uvs ((x + 1) / 2, (y + 1) / 2)
/// wound toward +z.
fn quads() -> Vec<u8> {
    let corners = vec![
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    write_serialized(&[
        (corners.clone(), vec![[0, 2, 1], [0, 3, 2]], vec![]),
        (
            corners,
            vec![[0, 1, 2], [0, 2, 3]],
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        ),
    ])
}

/// The PLY octahedron of mesh-attributes.xml (as bench/mitsuba_assets.py writes it), its
/// attributes named as Mitsuba's `write_ply` names them: a colour per vertex (`color_0`,
/// `color_1`, `color_2`), a colour and a weight (`weight_0`) per face.
const ATTRIBUTES_PLY: &str = "ply\n\
    format ascii 1.0\n\
    element vertex 6\n\
    property float x\n\
    property float y\n\
    property float z\n\
    property float color_0\n\
    property float color_1\n\
    property float color_2\n\
    element face 8\n\
    property list uchar int vertex_indices\n\
    property float color_0\n\
    property float color_1\n\
    property float color_2\n\
    property float weight_0\n\
    end_header\n\
    1 0 0 0.9 0.2 0.1\n\
    -1 0 0 0.1 0.8 0.2\n\
    0 1 0 0.2 0.3 0.9\n\
    0 -1 0 0.9 0.9 0.1\n\
    0 0 1 0.5 0.5 0.5\n\
    0 0 -1 0.1 0.1 0.1\n\
    3 0 2 4 0.8 0.1 0.1 0\n\
    3 2 1 4 0.1 0.7 0.1 0.25\n\
    3 1 3 4 0.1 0.2 0.8 0.5\n\
    3 3 0 4 0.7 0.7 0.1 0.75\n\
    3 2 0 5 0.1 0.6 0.6 1\n\
    3 1 2 5 0.6 0.1 0.6 0.1\n\
    3 3 1 5 0.9 0.5 0.2 0.6\n\
    3 0 3 5 0.3 0.3 0.3 0.9\n";

/// The PLY quad of mesh-uvs.xml (as bench/mitsuba_assets.py writes it): the same square
/// with normals +z and the same uvs.
const QUAD_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
    property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
    property float nz\nproperty float u\nproperty float v\nelement face 2\n\
    property list uchar int vertex_indices\nend_header\n\
    -1 -1 0 0 0 1 0 0\n1 -1 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n-1 1 0 0 0 1 0 1\n\
    3 0 1 2\n3 0 2 3\n";

/// The OBJ octahedron of shapes.xml (as bench/mitsuba_assets.py writes it): unit distance
/// from centre to vertex, faces wound outward, a normal per vertex along its axis.
fn octahedron() -> String {
    let mut s = String::from("v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n");
    s += "vn 1 0 0\nvn -1 0 0\nvn 0 1 0\nvn 0 -1 0\nvn 0 0 1\nvn 0 0 -1\n";
    for f in [
        [1, 3, 5],
        [3, 2, 5],
        [2, 4, 5],
        [4, 1, 5],
        [3, 1, 6],
        [2, 3, 6],
        [4, 2, 6],
        [1, 4, 6],
    ] {
        s += &format!("f {0}//{0} {1}//{1} {2}//{2}\n", f[0], f[1], f[2]);
    }
    s
}

/// tests/mitsuba copied into a fresh folder with its generated assets.
fn scenes(name: &str) -> PathBuf {
    let dir = common::tmp_dir(name);
    let src = common::repo_path("tests/mitsuba");
    for e in std::fs::read_dir(&src).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, dir.join(p.file_name().unwrap())).unwrap();
        }
    }
    let generated = dir.join("generated");
    std::fs::create_dir_all(&generated).unwrap();
    wgtrace::image_io::write_image(&generated.join("sky.exr"), 128, 64, &sky()).unwrap();
    wgtrace::image_io::write_image(&generated.join("waves.exr"), 64, 64, &waves()).unwrap();
    wgtrace::image_io::write_image(&generated.join("texels.exr"), 16, 8, &texels()).unwrap();
    std::fs::write(generated.join("pyramid.serialized"), pyramid()).unwrap();
    std::fs::write(generated.join("octahedron.obj"), octahedron()).unwrap();
    std::fs::write(generated.join("quads.serialized"), quads()).unwrap();
    std::fs::write(generated.join("quad.ply"), QUAD_PLY).unwrap();
    std::fs::write(generated.join("attributes.ply"), ATTRIBUTES_PLY).unwrap();
    std::fs::copy(
        common::repo_path("scenes/volumes/plume.vol"),
        generated.join("plume.vol"),
    )
    .unwrap();
    dir
}

fn rgb_of(path: &Path) -> (u32, u32, Vec<[f32; 3]>) {
    let exr = wgtrace::image_io::read_exr(path).unwrap_or_else(|e| panic!("{e}"));
    let ch = |n: &str| {
        &exr.channels
            .iter()
            .find(|c| c.0 == n)
            .unwrap_or_else(|| panic!("{}: no channel {n}", path.display()))
            .1
    };
    let (r, g, b) = (ch("R"), ch("G"), ch("B"));
    let px = (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect();
    (exr.width, exr.height, px)
}

type Render = fn(&wgtrace::FlatScene) -> wgtrace::Accumulation;

/// Renders `name`.xml from `dir` at `spp` with `render` and returns the share of pixels
/// and channels within the Sidak bound of Mitsuba's reference, with the worst few for the
/// message.
fn z_test(dir: &Path, name: &str, spp: u32, render: Render) -> (f64, String) {
    z_test_against(dir, name, name, false, spp, render)
}

/// [`z_test`] against the reference of scene `reference`, mirrored left to right if
/// `mirrored`.
fn z_test_against(
    dir: &Path,
    name: &str,
    reference: &str,
    mirrored: bool,
    spp: u32,
    render: Render,
) -> (f64, String) {
    let overrides = Overrides {
        spp: Some(spp),
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&dir.join(format!("{name}.xml")), &overrides)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let acc = render(&scene);
    let refs = common::repo_path("tests/mitsuba/refs");
    let (w, h, mut mean) = rgb_of(&refs.join(format!("{reference}.mean.exr")));
    let (_, _, mut se) = rgb_of(&refs.join(format!("{reference}.se.exr")));
    if mirrored {
        for row in mean.chunks_mut(w as usize).chain(se.chunks_mut(w as usize)) {
            row.reverse();
        }
    }
    assert_eq!((acc.width, acc.height), (w, h), "{name}: image size");
    let tests = mean.len() * 3;
    let bound = common::sidak_z(0.01, tests);
    let mut within = 0;
    let mut worst: Vec<(f64, String)> = Vec::new();
    for i in 0..mean.len() {
        let (m, v, n) = (acc.mean(i), acc.variance(i), acc.samples(i).max(1.0));
        for c in 0..3 {
            let sw = (v[c] as f64 / n as f64).sqrt();
            let d = m[c] as f64 - mean[i][c] as f64;
            // a pixel without variance (one that sees only an emitter) differs by the
            // rounding of f32 sums: n values summed in f32 are within n 2^-24 (f32's unit
            // roundoff) of it, relatively
            let rounding = n as f64
                * (f32::EPSILON as f64 / 2.0)
                * (m[c] as f64).abs().max(mean[i][c].abs() as f64);
            let z = d / (sw * sw + (se[i][c] as f64).powi(2) + rounding * rounding + 1e-12).sqrt();
            if z.abs() <= bound {
                within += 1;
            } else {
                let (x, y) = (i as u32 % w, i as u32 / w);
                worst.push((
                    z.abs(),
                    format!(
                        "pixel ({x}, {y}) {}: {:.4} against {:.4} (z {z:+.1})",
                        ["R", "G", "B"][c],
                        m[c],
                        mean[i][c]
                    ),
                ));
            }
        }
    }
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    let listed: Vec<String> = worst.iter().take(6).map(|w| w.1.clone()).collect();
    (within as f64 / tests as f64, listed.join("; "))
}

/// The scene agrees with Mitsuba's image on both backends.
fn agrees_with_mitsuba(name: &str, spp: u32) {
    let dir = scenes(name);
    for (backend, render) in [
        ("cpu", common::render_cpu as Render),
        ("gpu", common::render_gpu),
    ] {
        let (share, worst) = z_test(&dir, name, spp, render);
        eprintln!(
            "{name} ({backend}): {:.2}% within; worst: {worst}",
            share * 100.0
        );
        assert!(
            share >= 0.9975,
            "{name} ({backend}): {:.2}% of pixels and channels within the bound (99.75% \
             asked); worst: {worst}",
            share * 100.0
        );
    }
}

#[test]
fn legacy_cornell_box_agrees_with_mitsuba() {
    agrees_with_mitsuba("cornell-legacy", 256);
}

#[test]
fn materials_agree_with_mitsuba() {
    agrees_with_mitsuba("materials", 256);
}

/// envmap-texels.xml: an envmap's texel grid lies where Mitsuba's does.
#[test]
fn envmap_texels_lie_where_mitsuba_puts_them() {
    agrees_with_mitsuba("envmap-texels", 256);
}

#[test]
fn shapes_and_instances_agree_with_mitsuba() {
    agrees_with_mitsuba("shapes", 256);
}

/// mesh-uvs.xml: PLY and .serialized uvs with v down, a file's default barycentric uvs,
/// and the front of a mirrored mesh without the file's normals, as Mitsuba reads them.
#[test]
fn mesh_files_uvs_and_mirrored_fronts_agree_with_mitsuba() {
    agrees_with_mitsuba("mesh-uvs", 256);
}

#[test]
fn normal_maps_agree_with_mitsuba() {
    agrees_with_mitsuba("normalmap", 256);
}

/// normalmap-sphere.xml: a normal-mapped sphere whose terminator and rim show, where
/// Mitsuba's normalmap flips, loses and shadows (`shading_normals = "strict"`).
#[test]
fn normal_maps_at_the_rim_and_the_terminator_agree_with_mitsuba() {
    agrees_with_mitsuba("normalmap-sphere", 256);
}

/// spot-texture.xml: a spot projecting an image, turned about its axis, and a plain one.
#[test]
fn textured_spots_agree_with_mitsuba() {
    agrees_with_mitsuba("spot-texture", 256);
}

#[test]
fn environment_and_thin_lens_agree_with_mitsuba() {
    agrees_with_mitsuba("environment", 256);
}

#[test]
fn checkerboards_read_as_scalars_agree_with_mitsuba() {
    agrees_with_mitsuba("checker-scalars", 256);
}

/// glass-tints.xml: smooth, rough and thin glass with their reflection and transmission
/// tinted apart, under the default Gaussian film, whose samples both splat.
#[test]
fn glass_tinted_apart_and_splatted_samples_agree_with_mitsuba() {
    agrees_with_mitsuba("glass-tints", 256);
}

/// PLY attributes named as Mitsuba writes them (face_weight as a blend's weight,
/// face_color, vertex_color), under a splatting Gaussian film.
#[test]
fn mesh_attributes_agree_with_mitsuba() {
    agrees_with_mitsuba("mesh-attributes", 64);
}

/// Media as volpath renders them: a camera in a haze, a null-bounded fog of chromatic
/// extinction scattering forward, a glass sphere holding another medium nested in it, a
/// sphere half in and half out, lit by a point light and a spot. At 1024 spp: a pixel's
/// bound takes its standard error from the render's own sample variance, which at 256 spp
/// missed the rare long paths of a few pixels (99.11% within on the CPU, the deficit
/// all on wgtrace's low side; 8 runs of 256 spp against Mitsuba put 100.00% within).
#[test]
fn media_agree_with_mitsuba() {
    agrees_with_mitsuba("media", 1024);
}

#[test]
fn smoke_agrees_with_mitsuba() {
    agrees_with_mitsuba("smoke", 4096);
}

#[test]
fn film_crop_windows_agree_with_mitsuba() {
    agrees_with_mitsuba("crop", 256);
}

/// The z-test can fail: a reflectance changed by 5% is caught.
#[test]
fn a_changed_scene_fails_the_z_test() {
    let dir = scenes("mitsuba-changed");
    let path = dir.join("cornell-legacy.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    let changed = text.replace("0.73 0.73 0.73", "0.69 0.69 0.69");
    assert_ne!(text, changed);
    std::fs::write(&path, changed).unwrap();
    let (share, _) = z_test(&dir, "cornell-legacy", 256, common::render_cpu);
    assert!(share < 0.9975, "{:.2}% within", share * 100.0);
}

/// A camera whose to_world mirrors (a scale of -1 along its x before the lookat) shows
/// the mirror image, as Mitsuba renders it: the Cornell box's reference flipped left to
/// right.
#[test]
fn a_mirrored_camera_shows_the_mirror_image() {
    let dir = scenes("mitsuba-mirror");
    let text = std::fs::read_to_string(dir.join("cornell-legacy.xml")).unwrap();
    let mirrored = text.replace("<lookat origin", "<scale x=\"-1\"/><lookat origin");
    assert_ne!(text, mirrored);
    std::fs::write(dir.join("mirrored.xml"), mirrored).unwrap();
    let (share, worst) = z_test_against(
        &dir,
        "mirrored",
        "cornell-legacy",
        true,
        256,
        common::render_cpu,
    );
    assert!(share >= 0.9975, "{:.2}%: {worst}", share * 100.0);
}

/// A z-up scene: environment.xml with every to_world, the envmap's too, followed by a
/// quarter turn about x (the environment's up is then +z, a turn wgtrace's environment
/// cannot make about +y alone). The importer turns the whole scene back so the environment
/// turns about +y: the image is environment.xml's, judged against its Mitsuba reference.
/// A to_world that shears is refused at the envmap.
#[test]
fn an_environment_turned_with_a_z_up_scene_renders_as_the_y_up_one() {
    let dir = scenes("mitsuba-zup");
    let text = std::fs::read_to_string(dir.join("environment.xml")).unwrap();
    let quarter = "<rotate x=\"1\" angle=\"90\"/>";
    let mut zup = text.replace("</transform>", &format!("{quarter}</transform>"));
    // to_uv is a texture's, not a placement: as it was
    zup = zup.replace(
        &format!("<translate x=\"0.25\" y=\"0.1\"/>\n                {quarter}"),
        "<translate x=\"0.25\" y=\"0.1\"/>\n                ",
    );
    zup = zup.replace(
        "<float name=\"radius\" value=\"0.5\"/>",
        &format!("<float name=\"radius\" value=\"0.5\"/><transform name=\"to_world\">{quarter}</transform>"),
    );
    assert_eq!(zup.matches(quarter).count(), 6, "{zup}");
    std::fs::write(dir.join("zup.xml"), &zup).unwrap();
    let (share, worst) = z_test_against(&dir, "zup", "environment", false, 256, common::render_cpu);
    assert!(share >= 0.9975, "{:.2}%: {worst}", share * 100.0);
    let sheared = zup.replace(
        "<rotate y=\"1\" angle=\"60\"/>",
        "<rotate y=\"1\" angle=\"60\"/><matrix value=\"1 0.3 0 0 0 1 0 0 0 0 1 0 0 0 0 1\"/>",
    );
    std::fs::write(dir.join("sheared.xml"), sheared).unwrap();
    let e = wgtrace::load_scene(&dir.join("sheared.xml"), &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sheared.xml:") && e.contains("emitter envmap"),
        "{e}"
    );
}

#[test]
fn convert_writes_toml_that_loads_and_names_its_origins() {
    let dir = scenes("mitsuba-convert");
    let out = dir.join("shapes.toml");
    let o = common::wgtrace(&[
        "convert",
        dir.join("shapes.xml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-D",
        "spp=7",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let toml = std::fs::read_to_string(&out).unwrap();
    assert!(toml.contains("spp = 7"), "{toml}");
    // without -o it writes beside the scene, and never over a file there
    let xml = dir.join("shapes.xml");
    std::fs::remove_file(&out).unwrap();
    let beside = common::wgtrace(&["convert", xml.to_str().unwrap()]);
    assert!(
        beside.status.success(),
        "{}",
        String::from_utf8_lossy(&beside.stderr)
    );
    assert!(out.exists());
    std::fs::write(&out, "# edited\n").unwrap();
    let again = common::wgtrace(&["convert", xml.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(1), "{err}");
    assert!(err.contains("shapes.toml: exists"), "{err}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "# edited\n");
    std::fs::write(&out, &toml).unwrap();
    // the shapegroup is written once, as a group, and each instance places it
    assert_eq!(toml.matches("type = \"instance\"").count(), 3, "{toml}");
    assert!(toml.contains("group = \"pair\""), "{toml}");
    assert!(
        toml.contains("[[groups.pair.objects]]  # shape sphere, shapes.xml:"),
        "{toml}"
    );
    assert!(
        toml.contains("path = \"generated/pyramid.serialized\""),
        "{toml}"
    );
    assert!(toml.contains("shape_index = 1"), "{toml}");
    // the converted file renders as the XML does: the same records
    let a = wgtrace::load_scene(&out, &Overrides::default()).unwrap();
    let b = wgtrace::load_scene(&dir.join("shapes.xml"), &Overrides::default()).unwrap();
    assert_eq!(a.primitives.len(), b.primitives.len());
    assert_eq!(a.primitives, b.primitives);
}

/// Bad files: one error naming the file, line and column (and the element), exit 1.
#[test]
fn bad_files_are_one_error_with_the_position() {
    let dir = common::tmp_dir("mitsuba-bad");
    std::fs::copy(
        common::repo_path("scenes/volumes/plume.vol"),
        dir.join("g.vol"),
    )
    .unwrap();
    let scene = |body: &str| {
        format!(
            "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" \
             value=\"40\"/></sensor>\n{body}\n</scene>\n"
        )
    };
    let cases = [
        (
            "unknown-plugin",
            scene("<shape type=\"hair\"/>"),
            "3:1",
            "shape hair",
        ),
        (
            "missing-mesh",
            scene("<shape type=\"obj\"><string name=\"filename\" value=\"nope.obj\"/></shape>"),
            "3:19",
            "no such file",
        ),
        (
            "no-default",
            scene("<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>"),
            "3:",
            "$r",
        ),
        (
            "malformed",
            scene("<shape type=\"sphere\"><float name=\"radius\" value=\"1..5\"/></shape>"),
            "3:",
            "1..5",
        ),
        (
            "cyclic-ref",
            scene(
                "<bsdf type=\"twosided\" id=\"a\"><ref id=\"b\"/></bsdf>\n\
                 <bsdf type=\"twosided\" id=\"b\"><ref id=\"a\"/></bsdf>",
            ),
            "4:30",
            "cyclic reference",
        ),
        (
            "medium",
            scene(
                "<shape type=\"sphere\"><medium type=\"heterogeneous\" name=\"interior\">\
                 <phase type=\"rayleigh\"/></medium></shape>",
            ),
            "3:67",
            "phase rayleigh: not read (wgtrace reads isotropic and hg)",
        ),
        (
            "albedo-grid",
            scene(
                "<shape type=\"sphere\"><medium type=\"heterogeneous\" name=\"interior\">\
                 <volume type=\"gridvolume\" name=\"sigma_t\"><string name=\"filename\" value=\"g.vol\"/></volume>\
                 <volume type=\"gridvolume\" name=\"albedo\"><string name=\"filename\" value=\"g.vol\"/>\
                 <transform name=\"to_world\"><scale value=\"2\"/></transform></volume></medium></shape>",
            ),
            "3:156",
            "an albedo grid is read with a density grid (`sigma_t`) placed the same way",
        ),
        (
            "crop",
            "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n<film type=\"hdrfilm\">\
             <integer name=\"width\" value=\"8\"/><integer name=\"crop_width\" value=\"9\"/>\
             </film></sensor>\n</scene>\n"
                .to_string(),
            "3:1",
            "crop window",
        ),
        (
            "bad-value",
            scene("<shape type=\"sphere\"><float name=\"radius\" value=\"-1\"/></shape>"),
            "3:1",
            "shape sphere (converted: objects[0].radius)",
        ),
    ];
    for (name, text, at, says) in cases {
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(&path, text).unwrap();
        let png = dir.join(format!("{name}.png"));
        let o = common::wgtrace(&[
            "render",
            path.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        let lead = format!("{}:{at}", path.display());
        assert!(err.contains(&lead), "{name}: expected {lead} in: {err}");
        assert!(err.contains(says), "{name}: expected `{says}` in: {err}");
    }
}

#[test]
fn serialized_meshes_read_back() {
    let bytes = pyramid();
    let m = wgtrace::scene::mesh::read_serialized(&bytes, 1).unwrap();
    assert_eq!(m.positions.len(), 5);
    assert_eq!(m.triangles.len(), 6);
    assert_eq!(m.triangles[2], [0, 4, 1]);
    let first = wgtrace::scene::mesh::read_serialized(&bytes, 0).unwrap();
    assert_eq!(first.triangles, vec![[0, 1, 2]]);
    let e = wgtrace::scene::mesh::read_serialized(&bytes, 2).unwrap_err();
    assert!(e.contains("has 2 meshes"), "{e}");
    let e = wgtrace::scene::mesh::read_serialized(&bytes[..bytes.len() / 2], 1).unwrap_err();
    assert!(!e.is_empty());
    let e = wgtrace::scene::mesh::read_serialized(b"PK\x03\x04", 0).unwrap_err();
    assert!(e.contains("0x041C"), "{e}");
}

/// Spectra become the colours Mitsuba 3.9.1's scalar_rgb variant gives them when it loads
/// the same values (mi.traverse of a diffuse reflectance and of an area emitter's
/// radiance): a list integrated against the CIE curves, weighted by D65 outside emitters;
/// a constant in an emitter times the sRGB colour of a flat spectrum.
#[test]
fn spectra_convert_as_mitsuba_rgb_mode() {
    use wgtrace::scene::mitsuba::spectrum::{named_ior, to_rgb, Use};
    use wgtrace::scene::mitsuba::Spectrum;
    let s = Spectrum::Samples(vec![(400.0, 0.2), (500.0, 0.5), (600.0, 0.7), (700.0, 0.9)]);
    let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 2e-5);
    let r = to_rgb(&s, Use::Reflectance);
    assert!(close(r, [0.778248, 0.589654, 0.328566]), "{r:?}");
    let e = to_rgb(&s, Use::Emission);
    assert!(close(e, [0.921007, 0.561588, 0.290428]), "{e:?}");
    let u = to_rgb(&Spectrum::Uniform(2.0), Use::Emission);
    assert!(close(u, [2.40959, 1.89658, 1.81783]), "{u:?}");
    assert_eq!(to_rgb(&Spectrum::Uniform(0.3), Use::Reflectance), [0.3; 3]);
    // bk7 over water, as Mitsuba's dielectric reports its eta
    let eta = named_ior("bk7").unwrap() / named_ior("Water").unwrap();
    assert!((eta - 1.1287323).abs() < 1e-6);
    assert_eq!(named_ior("unobtainium"), None);
}

/// An envmap turned about +y by a, rendered by wgtrace turned by a + 180 (Mitsuba's image
/// centre faces +z, wgtrace's -z) with its rows moved onto Mitsuba's (its first and last on
/// the poles; envmap-texels.xml checks the grid against Mitsuba's image); a
/// bitmap's to_uv conjugated by the v flip (an offset of 0.25 in Mitsuba's v, which runs
/// down, is -0.25 in wgtrace's); an envmap turned about x turns the scene back with it.
#[test]
fn envmaps_turn_and_uv_transforms_flip() {
    let dir = scenes("mitsuba-envmap");
    let xml = |turn: &str| {
        format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="40"/></sensor>
<emitter type="envmap"><string name="filename" value="generated/sky.exr"/>
<transform name="to_world"><rotate {turn} angle="30"/></transform></emitter>
<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
<string name="filename" value="generated/sky.exr"/>
<transform name="to_uv"><translate x="0.5" y="0.25"/></transform></texture></bsdf></shape>
</scene>"#
        )
    };
    let path = dir.join("turned.xml");
    std::fs::write(&path, xml("y=\"1\"")).unwrap();
    let out = wgtrace::scene::load::convert_mitsuba(&path, &[], &dir).unwrap();
    assert!(out.toml.contains("rotation = 210.0"), "{}", out.toml);
    // 128 x 64 texels: the rows spread over theta as Mitsuba's, the columns where they were
    assert!(
        out.toml
            .contains("matrix = [[1.0, 0.0, 0.0], [0.0, 0.984375, 0.0078125]]"),
        "{}",
        out.toml
    );
    assert!(
        out.toml
            .contains("matrix = [[1.0, 0.0, 0.5], [0.0, 1.0, -0.25]]"),
        "{}",
        out.toml
    );
    // turned about x: the scene turns back with it, the environment about +y only
    std::fs::write(&path, xml("x=\"1\"")).unwrap();
    let out = wgtrace::scene::load::convert_mitsuba(&path, &[], &dir).unwrap();
    assert!(out.toml.contains("rotation = 180.0"), "{}", out.toml);
    assert!(out.toml.contains("transform = "), "{}", out.toml);
}

/// A sensor's near_clip becomes the camera's (times the length of its z axis under
/// to_world, as Mitsuba's rays leave the plane), Mitsuba's 0.01 when it has none;
/// far_clip is noted, since wgtrace's rays are not cut off; near_clip past far_clip is
/// an error at the sensor's position.
#[test]
fn near_clip_is_the_cameras_and_far_clip_a_note() {
    let dir = scenes("mitsuba-clip");
    let xml = |clip: &str| {
        format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="40"/>{clip}
<transform name="to_world"><scale value="2"/></transform></sensor>
<shape type="sphere"/>
</scene>"#
        )
    };
    let path = dir.join("clip.xml");
    let convert = |clip: &str| {
        std::fs::write(&path, xml(clip)).unwrap();
        wgtrace::scene::load::convert_mitsuba(&path, &[], &dir)
    };
    let plain = convert("").unwrap();
    assert!(plain.toml.contains("near_clip = 0.02"), "{}", plain.toml);
    let set =
        convert(r#"<float name="near_clip" value="1.5"/><float name="far_clip" value="50"/>"#)
            .unwrap();
    assert!(set.toml.contains("near_clip = 3.0"), "{}", set.toml);
    assert!(
        set.notes.iter().any(|n| n.contains("far_clip 50")),
        "{:?}",
        set.notes
    );
    let e = convert(r#"<float name="near_clip" value="60"/><float name="far_clip" value="50"/>"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("clip.xml:2:1") && e.contains("near_clip"), "{e}");
}

/// What Bitterli's living-room-2 writes: a mask's opacity as an <rgb>, read as a scalar
/// by its luminance (Mitsuba's eval_1), and a rough conductor's eta and k with negative
/// components (an exporter's artefact), taken by their magnitudes with a note: the
/// Fresnel reflectance of eta + i k is that of its conjugate and of its negative.
#[test]
fn rgb_opacities_and_negative_conductor_indices_read_as_mitsuba_reads_them() {
    let dir = scenes("mitsuba-rgb-scalars");
    let path = dir.join("rgb-scalars.xml");
    std::fs::write(
        &path,
        r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="40"/></sensor>
<bsdf type="mask" id="shade"><rgb name="opacity" value="0.2, 0.5, 0.9"/><bsdf type="diffuse"/></bsdf>
<bsdf type="roughconductor" id="knob"><float name="alpha" value="0.1"/>
<rgb name="eta" value="-0.05, 4.1, 4.7"/><rgb name="k" value="-0.04, 0.09, 1.3"/></bsdf>
<shape type="sphere"><ref id="shade"/></shape>
<shape type="sphere"><point name="center" x="3" y="0" z="0"/><ref id="knob"/></shape>
</scene>"#,
    )
    .unwrap();
    let set = wgtrace::scene::load::convert_mitsuba(&path, &[], &dir).unwrap();
    let lum = 0.2126 * 0.2 + 0.7152 * 0.5 + 0.0722 * 0.9;
    let opacity: f64 = set
        .toml
        .lines()
        .find_map(|l| l.strip_prefix("opacity = "))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{}", set.toml));
    assert!((opacity - lum).abs() < 1e-6, "{opacity} against {lum}");
    assert!(set.toml.contains("eta = [0.05, 4.1, 4.7]"), "{}", set.toml);
    assert!(set.toml.contains("k = [0.04, 0.09, 1.3]"), "{}", set.toml);
    assert!(
        set.notes
            .iter()
            .any(|n| n.contains("5:1") && n.contains("`eta` has negative")),
        "{:?}",
        set.notes
    );
    wgtrace::load_scene(&path, &Overrides::default()).unwrap();
}

/// `wgtrace convert` of the scene file at `path`, as a user runs it: the TOML written
/// beside it (replacing one there).
fn converted(path: &Path) -> String {
    let out = path.with_extension("toml");
    let o = common::wgtrace(&[
        "convert",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(&out).unwrap()
}

/// What Mitsuba's own test scenes write: a colour as a `<spectrum type="srgb">` or
/// `type="uniform"` object (read as the same constant), a normalmap BSDF with a constant
/// map (the identity (0.5, 0.5, 1) leaves the nested BSDF alone, another colour becomes a
/// constant texture), and a mesh named in an included file found in the scene file's
/// folder, where Mitsuba's file resolver finds it, not beside the included file.
#[test]
fn spectrum_objects_constant_normal_maps_and_includes_read_as_mitsuba_reads_them() {
    let dir = common::tmp_dir("mitsuba-own-forms");
    std::fs::create_dir_all(dir.join("include")).unwrap();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("include/shapes.xml"),
        "<scene version=\"3.0.0\">\n<shape type=\"obj\"><string name=\"filename\" \
         value=\"meshes/tri.obj\"/></shape>\n</scene>\n",
    )
    .unwrap();
    let scene = |map: &str| {
        format!(
            "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n\
             <include filename=\"include/shapes.xml\"/>\n\
             <bsdf type=\"diffuse\" id=\"a\"><spectrum name=\"reflectance\" type=\"srgb\">\
             <rgb name=\"color\" value=\"0.2, 0.4, 0.6\"/></spectrum></bsdf>\n\
             <bsdf type=\"diffuse\" id=\"b\"><spectrum name=\"reflectance\" type=\"uniform\">\
             <float name=\"value\" value=\"0.3\"/></spectrum></bsdf>\n\
             <bsdf type=\"normalmap\" id=\"n\"><spectrum name=\"normalmap\" type=\"srgb\">\
             <rgb name=\"color\" value=\"{map}\"/></spectrum><bsdf type=\"diffuse\"/></bsdf>\n\
             <shape type=\"sphere\"><ref id=\"a\"/></shape>\n\
             <shape type=\"sphere\"><ref id=\"b\"/></shape>\n\
             <shape type=\"sphere\"><ref id=\"n\"/></shape>\n</scene>\n"
        )
    };
    let path = dir.join("scene.xml");
    let toml = |map: &str| {
        std::fs::write(&path, scene(map)).unwrap();
        converted(&path)
    };
    let identity = toml("0.5, 0.5, 1.0");
    assert!(identity.contains("albedo = [0.2, 0.4, 0.6]"), "{identity}");
    assert!(identity.contains("albedo = [0.3, 0.3, 0.3]"), "{identity}");
    assert!(!identity.contains("normal_map"), "{identity}");
    assert!(identity.contains("tri.obj"), "{identity}");
    let tilted = toml("0.6, 0.5, 0.9");
    assert!(tilted.contains("normal_map = \"normalmap"), "{tilted}");
    assert!(tilted.contains("type = \"constant\""), "{tilted}");
    // the scene's folder before the included file's: a decoy beside the include loses
    std::fs::create_dir_all(dir.join("include/meshes")).unwrap();
    std::fs::write(dir.join("include/meshes/tri.obj"), "not an obj\n").unwrap();
    std::fs::write(&path, scene("0.5, 0.5, 1.0")).unwrap();
    wgtrace::load_scene(&path, &Overrides::default()).unwrap();
}

/// Forms Mitsuba's own documentation scenes use, which Mitsuba renders: a perspective
/// camera with a focus_distance (every projective camera reads it; only thinlens uses
/// it), a shape's BSDF given by a named reference (`<ref name="bsdf" id=...>`), and an
/// area emitter declared at the top with an id and referenced from a shape (before its
/// declaration). An area emitter that no shape references is still refused.
#[test]
fn documentation_scene_forms_read_as_mitsuba_reads_them() {
    let dir = common::tmp_dir("mitsuba-doc-forms");
    let scene = |extra: &str| {
        format!(
            "<scene version=\"3.0.0\">\n\
             <sensor type=\"perspective\"><float name=\"focus_distance\" value=\"6\"/></sensor>\n\
             <bsdf type=\"diffuse\" id=\"grey\"/>\n\
             <shape type=\"sphere\"><ref name=\"bsdf\" id=\"grey\"/><ref id=\"glow\"/></shape>\n\
             <emitter type=\"area\" id=\"glow\"><rgb name=\"radiance\" value=\"2, 3, 4\"/></emitter>\n\
             {extra}</scene>\n"
        )
    };
    let path = dir.join("doc.xml");
    std::fs::write(&path, scene("")).unwrap();
    let toml = converted(&path);
    assert!(toml.contains("emission = [2.0, 3.0, 4.0]"), "{toml}");
    assert!(!toml.contains("focus_distance"), "{toml}");
    std::fs::write(
        &path,
        scene("<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>\n"),
    )
    .unwrap();
    let e = wgtrace::load_scene(&path, &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("doc.xml:6:1") && e.contains("belongs inside a shape"),
        "{e}"
    );
}

/// Mitsuba's film splats each sample over the pixels its filter reaches, weighed by the
/// filter itself (its llvm and cuda variants): a file's tent and Gaussian (the default,
/// with a film or without) become `reconstruction = "splat"` without steps, which the
/// loaded scene hands to both backends; the box (whose splat is the sample's own pixel)
/// and a film with `sample_border` (whose samples come from beyond the image) keep
/// drawing samples from the filter.
#[test]
fn mitsuba_films_splat_their_samples() {
    let dir = common::tmp_dir("mitsuba-filter-splat");
    let film = |rfilter: &str, border: &str| {
        format!(
            "<film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/>\
             <integer name=\"height\" value=\"8\"/>{border}{rfilter}</film>"
        )
    };
    let border = "<boolean name=\"sample_border\" value=\"true\"/>";
    for (name, film, kind, splat) in [
        ("default", film("", ""), "gaussian", true),
        ("no-film", String::new(), "gaussian", true),
        (
            "narrow",
            film(
                "<rfilter type=\"gaussian\"><float name=\"stddev\" value=\"0.25\"/></rfilter>",
                "",
            ),
            "gaussian",
            true,
        ),
        ("tent", film("<rfilter type=\"tent\"/>", ""), "tent", true),
        ("box", film("<rfilter type=\"box\"/>", ""), "box", false),
        ("border", film("", border), "gaussian", false),
    ] {
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(
            &path,
            format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n{film}\n</sensor>\n\
                 <shape type=\"sphere\"/>\n</scene>\n"
            ),
        )
        .unwrap();
        let toml = converted(&path);
        assert!(toml.contains(&format!("filter = \"{kind}\"")), "{toml}");
        assert!(!toml.contains("filter_steps"), "{name}: {toml}");
        let scene = wgtrace::load_scene(&path, &Overrides::default()).unwrap();
        assert_eq!(scene.filter.splat, splat, "{name}: {toml}");
        assert_eq!(scene.params(0, scene.full_band()).splat, splat as u32);
    }
}

/// A heterogeneous medium's constant extinction fills the unit cube its constvolume's
/// to_world places (Mitsuba's medium ends at the volume's box): the conversion keeps the
/// medium heterogeneous, without a grid, placed by that transform.
#[test]
fn a_constant_heterogeneous_extinction_keeps_its_box() {
    let dir = common::tmp_dir("mitsuba-constvolume");
    let xml = dir.join("c.xml");
    std::fs::write(
        &xml,
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n\
         <shape type=\"cube\"><bsdf type=\"null\"/><medium type=\"heterogeneous\" name=\"interior\">\
         <volume type=\"constvolume\" name=\"sigma_t\"><rgb name=\"value\" value=\"0.5, 0.4, 0.3\"/>\
         <transform name=\"to_world\"><translate x=\"-0.5\" y=\"-0.5\" z=\"-0.5\"/></transform>\
         </volume></medium></shape>\n</scene>\n",
    )
    .unwrap();
    let toml = dir.join("c.toml");
    let o = common::wgtrace(&[
        "convert",
        xml.to_str().unwrap(),
        "-o",
        toml.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&toml).unwrap();
    let medium = &text[text.find("[media.").expect("a medium")..];
    assert!(medium.contains("type = \"heterogeneous\""), "{medium}");
    assert!(!medium.contains("grid ="), "{medium}");
    assert!(
        medium.contains("[1.0, 0.0, 0.0, -0.5], [0.0, 1.0, 0.0, -0.5], [0.0, 0.0, 1.0, -0.5]"),
        "{medium}"
    );
}

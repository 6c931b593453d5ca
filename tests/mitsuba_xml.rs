//! The Mitsuba 3 XML reader (`scene::mitsuba`): every value kind, defaults and `$name`
//! substitution with `-D` overrides, references before and after their objects, aliases,
//! includes and search paths, transforms composed in order, spectra, the upgrade of files
//! older than Mitsuba 2, and one error naming file, line and column for each kind of bad
//! file the importer must refuse.

use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3};
use proptest::prelude::*;
use wgtrace::scene::mitsuba::{parse_str, snake_case, SceneTree, Spectrum, Value, XmlError};

fn parse(text: &str) -> Result<SceneTree, XmlError> {
    parse_str(text, Path::new("test.xml"), &[])
}

fn ok(text: &str) -> SceneTree {
    parse(text).unwrap_or_else(|e| panic!("{e}"))
}

/// The error of a bad file, which must name test.xml at `line`.
fn err(text: &str, line: u32) -> String {
    let e = parse(text).expect_err("a bad file");
    assert_eq!(e.pos.file.as_path(), Path::new("test.xml"), "{e}");
    assert_eq!(e.pos.line, line, "{e}");
    assert!(e.pos.col >= 1, "{e}");
    e.to_string()
}

fn value<'a>(t: &'a SceneTree, object: usize, name: &str) -> &'a Value {
    &t.objects[object]
        .get(name)
        .unwrap_or_else(|| panic!("no {name}"))
        .value
}

fn child(t: &SceneTree, object: usize, name: &str) -> usize {
    match value(t, object, name) {
        Value::Object(i) => *i,
        v => panic!("{name} is {v:?}"),
    }
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-12
}

#[test]
fn every_value_kind_reads_as_written() {
    let t = ok(r#"<?xml version="1.0"?>
<!-- a comment -->
<scene version="3.0.0">
    <integrator type="path">
        <integer name="max_depth" value="-1"/>
        <boolean name="hide_emitters" value="True"/>
    </integrator>
    <shape type="sphere">
        <float name="radius" value="2.5e-1"/>
        <point name="center" x="1" z="3"/>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.1, 0.2 0.3"/>
        </bsdf>
        <string name="label" value="a b"/>
    </shape>
    <emitter type="point">
        <point name="position" value="1 2 3"/>
        <vector name="direction" value="0.5"/>
        <rgb name="intensity" value="4"/>
    </emitter>
</scene>"#);
    let root = &t.objects[t.root];
    assert_eq!(
        (root.tag.as_str(), root.plugin.as_str()),
        ("scene", "scene")
    );
    let integrator = child(&t, t.root, "_arg_0");
    assert_eq!(t.objects[integrator].plugin, "path");
    assert_eq!(value(&t, integrator, "max_depth"), &Value::Integer(-1));
    assert_eq!(
        value(&t, integrator, "hide_emitters"),
        &Value::Boolean(true)
    );
    let sphere = child(&t, t.root, "_arg_1");
    assert_eq!(value(&t, sphere, "radius"), &Value::Float(0.25));
    assert_eq!(
        value(&t, sphere, "center"),
        &Value::Point(DVec3::new(1.0, 0.0, 3.0))
    );
    assert_eq!(value(&t, sphere, "label"), &Value::String("a b".into()));
    let bsdf = child(&t, sphere, "_arg_0");
    assert_eq!(t.objects[bsdf].tag, "bsdf");
    assert_eq!(
        value(&t, bsdf, "reflectance"),
        &Value::Rgb(DVec3::new(0.1, 0.2, 0.3))
    );
    let emitter = child(&t, t.root, "_arg_2");
    assert_eq!(
        value(&t, emitter, "position"),
        &Value::Point(DVec3::new(1.0, 2.0, 3.0))
    );
    assert_eq!(
        value(&t, emitter, "direction"),
        &Value::Vector(DVec3::splat(0.5))
    );
    assert_eq!(
        value(&t, emitter, "intensity"),
        &Value::Rgb(DVec3::splat(4.0))
    );
    // positions: the sphere's element starts on line 8
    assert_eq!(t.objects[sphere].pos.line, 8);
}

#[test]
fn defaults_and_defines_substitute_the_longest_names_first() {
    let text = r#"<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="sppx" value="7"/>
    <default name="res" value="128"/>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$sppx"/></film>
</scene>"#;
    let t = ok(text);
    let sampler = child(&t, t.root, "_arg_0");
    let film = child(&t, t.root, "_arg_1");
    assert_eq!(value(&t, sampler, "sample_count"), &Value::Integer(64));
    assert_eq!(value(&t, film, "height"), &Value::Integer(7));
    // -D overrides the file's default
    let t = parse_str(text, Path::new("test.xml"), &[("spp".into(), "16".into())]).unwrap();
    let sampler = child(&t, t.root, "_arg_0");
    assert_eq!(value(&t, sampler, "sample_count"), &Value::Integer(16));
    // a define no $name uses is refused, as Mitsuba refuses it: one with a <default> too
    for name in ["sp", "unknown"] {
        let e = parse_str(text, Path::new("test.xml"), &[(name.into(), "16".into())])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("test.xml:1:1: -D ") && e.contains("uses no such $parameter"),
            "{e}"
        );
    }
    let unused = text.replace("value=\"$res\"", "value=\"128\"");
    let e = parse_str(
        &unused,
        Path::new("test.xml"),
        &[("res".into(), "256".into())],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("-D res=256: the scene uses no such $parameter"),
        "{e}"
    );
}

#[test]
fn references_resolve_before_and_after_their_objects_and_aliases_share_them() {
    let t = ok(r#"<scene version="3.0.0">
    <shape type="sphere"><ref id="later" name="bsdf"/></shape>
    <bsdf type="diffuse" id="later"/>
    <alias id="later" as="again"/>
    <shape type="cube"><ref id="again"/></shape>
</scene>"#);
    let a = child(&t, t.root, "_arg_0");
    let b = child(&t, t.root, "_arg_2");
    let bsdf = child(&t, a, "bsdf");
    assert_eq!(t.objects[bsdf].id.as_deref(), Some("later"));
    assert_eq!(child(&t, b, "_arg_0"), bsdf);
}

#[test]
fn transforms_compose_in_the_order_written() {
    let t = ok(r#"<scene version="3.0.0">
    <shape type="sphere">
        <transform name="to_world">
            <scale value="2"/>
            <rotate z="1" angle="90"/>
            <translate x="1" y="0" z="0"/>
        </transform>
    </shape>
    <shape type="sphere">
        <transform name="to_world">
            <matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>
        </transform>
    </shape>
    <sensor type="perspective">
        <transform name="to_world">
            <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
    </sensor>
</scene>"#);
    let m = |o: &str| match value(&t, child(&t, t.root, o), "to_world") {
        Value::Transform(m) => *m,
        v => panic!("{v:?}"),
    };
    // (1, 0, 0) scaled to (2, 0, 0), turned to (0, 2, 0), moved to (1, 2, 0)
    assert!(close(
        m("_arg_0").transform_point3(DVec3::X),
        DVec3::new(1.0, 2.0, 0.0)
    ));
    // row-major in the file
    assert!(close(
        m("_arg_1").transform_point3(DVec3::ZERO),
        DVec3::new(5.0, 6.0, 7.0)
    ));
    // the camera's z looks at the target, its y is up, at the origin given
    let look = m("_arg_2");
    assert!(close(
        look.transform_point3(DVec3::ZERO),
        DVec3::new(0.0, 0.0, 5.0)
    ));
    assert!(close(look.transform_vector3(DVec3::Z), -DVec3::Z));
    assert!(close(look.transform_vector3(DVec3::Y), DVec3::Y));
    let _: DMat4 = look;
}

#[test]
fn spectra_are_constants_or_increasing_wavelength_pairs() {
    let dir = scratch("spectra");
    std::fs::write(dir.join("s.spd"), "# a comment\n400 0.5\n700 0.25\n").unwrap();
    let xml = dir.join("scene.xml");
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0">
    <bsdf type="diffuse">
        <spectrum name="a" value="0.5"/>
        <spectrum name="b" value="400:0.1, 500:0.2 600:0.3"/>
        <spectrum name="c" filename="s.spd"/>
    </bsdf>
</scene>"#,
    )
    .unwrap();
    let t = wgtrace::scene::mitsuba::parse_file(&xml, &[]).unwrap();
    let b = child(&t, t.root, "_arg_0");
    assert_eq!(value(&t, b, "a"), &Value::Spectrum(Spectrum::Uniform(0.5)));
    assert_eq!(
        value(&t, b, "b"),
        &Value::Spectrum(Spectrum::Samples(vec![
            (400.0, 0.1),
            (500.0, 0.2),
            (600.0, 0.3)
        ]))
    );
    assert_eq!(
        value(&t, b, "c"),
        &Value::Spectrum(Spectrum::Samples(vec![(400.0, 0.5), (700.0, 0.25)]))
    );
}

/// A fresh folder under target/ for files a test writes.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("mitsuba-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn includes_splice_a_scene_in_place_and_paths_find_files() {
    let dir = scratch("include");
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::write(
        dir.join("parts/materials.xml"),
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="white"/></scene>"#,
    )
    .unwrap();
    std::fs::write(dir.join("parts/light.xml"), r#"<emitter type="constant"/>"#).unwrap();
    let xml = dir.join("scene.xml");
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0">
    <path value="parts"/>
    <include filename="materials.xml"/>
    <include filename="light.xml"/>
    <shape type="sphere"><ref id="white"/></shape>
</scene>"#,
    )
    .unwrap();
    let t = wgtrace::scene::mitsuba::parse_file(&xml, &[]).unwrap();
    // the <path> folders first, then the scene file's own (Mitsuba's file resolver)
    assert_eq!(t.search_paths, vec![dir.join("parts"), dir.clone()]);
    let bsdf = child(&t, t.root, "_arg_0");
    assert_eq!(t.objects[bsdf].id.as_deref(), Some("white"));
    assert_eq!(t.objects[child(&t, t.root, "_arg_1")].plugin, "constant");
    assert_eq!(child(&t, child(&t, t.root, "_arg_2"), "_arg_0"), bsdf);
    // an include of itself stops at the depth limit with the file and line of the include
    std::fs::write(
        dir.join("loop.xml"),
        "<scene version=\"3.0.0\">\n<include filename=\"loop.xml\"/>\n</scene>",
    )
    .unwrap();
    let e = wgtrace::scene::mitsuba::parse_file(&dir.join("loop.xml"), &[]).unwrap_err();
    assert!(e.to_string().contains("deeper than 15"), "{e}");
    assert_eq!(e.pos.line, 2, "{e}");
}

#[test]
fn files_older_than_mitsuba_2_are_upgraded_as_mitsuba_upgrades_them() {
    let t = ok(r#"<scene version="0.5.0">
    <bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.5"/></bsdf>
    <bsdf type="dielectric"><float name="intIOR" value="1.5"/></bsdf>
    <texture type="bitmap"><float name="uscale" value="4"/><float name="voffset" value="0.5"/></texture>
    <sensor type="perspective"><transform name="toWorld"><lookAt origin="0 0 1" target="0 0 0"/></transform></sensor>
</scene>"#);
    assert_eq!(
        value(&t, child(&t, t.root, "_arg_0"), "reflectance"),
        &Value::Rgb(DVec3::splat(0.5))
    );
    assert_eq!(
        value(&t, child(&t, t.root, "_arg_1"), "int_ior"),
        &Value::Float(1.5)
    );
    let texture = child(&t, t.root, "_arg_2");
    let Value::Transform(m) = value(&t, texture, "to_uv") else {
        panic!()
    };
    // (u, v) + offset, then scaled: (0, 0) -> (0, 0.5) -> (0, 0.5)
    assert!(close(
        m.transform_point3(DVec3::ZERO),
        DVec3::new(0.0, 0.5, 0.0)
    ));
    assert!(close(
        m.transform_point3(DVec3::X),
        DVec3::new(4.0, 0.5, 0.0)
    ));
    assert!(t.objects[texture].get("uscale").is_none());
    let sensor = child(&t, t.root, "_arg_3");
    assert!(matches!(value(&t, sensor, "to_world"), Value::Transform(_)));
    assert_eq!(snake_case("diffuseReflectance"), "diffuse_reflectance");
    assert_eq!(snake_case("intIOR"), "int_ior");
    assert_eq!(snake_case("aBcD"), "a_bcD");
    assert_eq!(snake_case("radius"), "radius");
}

#[test]
fn bad_files_are_one_error_naming_file_line_and_column() {
    let e = err("<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n<float name=\"radius\" value=\"1.5x\"/>\n</shape></scene>", 3);
    assert!(e.contains("\"1.5x\" is not a finite number"), "{e}");
    let e = err("<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n<flaot name=\"radius\" value=\"1\"/>\n</shape></scene>", 3);
    assert!(e.contains("unknown element <flaot>"), "{e}");
    let e = err(
        "<scene version=\"3.0.0\">\n\n<integer name=\"spp\" value=\"$spp\"/></scene>",
        3,
    );
    assert!(e.contains("undefined parameter"), "{e}");
    let e = err(
        "<scene version=\"3.0.0\">\n<bsdf type=\"twosided\" id=\"a\"><ref id=\"b\"/></bsdf>\n<bsdf type=\"twosided\" id=\"b\">\n<ref id=\"a\"/></bsdf></scene>",
        4,
    );
    assert!(e.contains("cyclic reference"), "{e}");
    let e = err(
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\"><ref id=\"nothing\"/></shape></scene>",
        2,
    );
    assert!(e.contains("no object has that id"), "{e}");
    let e = err("<scene version=\"3.0.0\">\n<bsdf type=\"diffuse\" id=\"x\"/>\n<bsdf type=\"diffuse\" id=\"x\"/></scene>", 3);
    assert!(
        e.contains("duplicate id \"x\" (first at test.xml:2:1)"),
        "{e}"
    );
    let e = err("<scene>\n</scene>", 1);
    assert!(e.contains("version"), "{e}");
    let e = err("<scene version=\"3.0.0\">\n<shape type=\"obj\">\n<include filename=\"missing.xml\"/></shape></scene>", 3);
    assert!(e.contains("missing.xml"), "{e}");
    let e = err(
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\" colour=\"red\"/></scene>",
        2,
    );
    assert!(e.contains("unexpected attribute \"colour\""), "{e}");
    let e = err(
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n</scene>",
        3,
    );
    assert!(e.contains("not well-formed XML"), "{e}");
    let e = err("<scene version=\"3.0.0\">\n<translate x=\"1\"/></scene>", 2);
    assert!(e.contains("only stand in a <transform>"), "{e}");
    let e = err("<scene version=\"3.0.0\"><bsdf type=\"diffuse\">\n<spectrum name=\"r\" value=\"500:1 400:2\"/></bsdf></scene>", 2);
    assert!(e.contains("must increase"), "{e}");
}

/// A valid file with every construct the reader knows, for the fuzz test to break.
const FUZZ_BASE: &str = r#"<scene version="3.0.0">
    <default name="r" value="0.5"/>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf>
    <alias id="white" as="blanc"/>
    <shape type="sphere">
        <float name="radius" value="$r"/>
        <point name="center" x="0" y="1" z="2"/>
        <ref id="blanc"/>
        <transform name="to_world"><rotate x="1" angle="30"/><scale value="2"/><matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"/></transform>
    </shape>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0 0 5" target="0 0 0" up="0 1 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><boolean name="banner" value="false"/></film>
    </sensor>
    <bsdf type="conductor"><spectrum name="eta" value="400:1.5 700:1.2"/><spectrum name="k" value="3"/></bsdf>
</scene>"#;

/// What an edit inserts: markup, quotes, names of things, bad numbers.
const FUZZ_TOKENS: &[&str] = &[
    "<",
    ">",
    "/>",
    "\"",
    "=",
    "$",
    "$r",
    "$x",
    "<ref id=\"white\"/>",
    "<ref id=\"none\"/>",
    "<include filename=\"none.xml\"/>",
    "nan",
    "inf",
    "-1e400",
    "1,2",
    ":",
    "<transform name=\"t\">",
    "</shape>",
    "<shape type=\"cube\">",
    "id=\"white\"",
    "<!--",
    "-->",
    "&amp;",
    "&bad;",
    "version=\"1.0.0\"",
    "<lookat origin=\"0 0 0\" target=\"0 0 0\"/>",
    "<rotate angle=\"1\"/>",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Broken files give an error naming the file and a line (never a panic); files that
    /// parse are mapped onto the scene format and loaded, without a panic either.
    #[test]
    fn the_reader_never_panics_on_broken_files(
        edits in proptest::collection::vec((any::<proptest::sample::Index>(), 0..FUZZ_TOKENS.len(), any::<bool>()), 1..6)
    ) {
        let mut text = FUZZ_BASE.to_string();
        for (at, token, delete) in edits {
            let mut i = at.index(text.len() + 1);
            while !text.is_char_boundary(i) {
                i -= 1;
            }
            if delete {
                let mut j = (i + 3).min(text.len());
                while !text.is_char_boundary(j) {
                    j += 1;
                }
                text.replace_range(i..j, "");
            } else {
                text.insert_str(i, FUZZ_TOKENS[token]);
            }
        }
        match parse(&text) {
            Err(e) => {
                prop_assert!(e.pos.line >= 1 && e.to_string().starts_with("test.xml:"), "{}", e);
            }
            // what parses goes on through the mapping onto the scene format, and what
            // that makes through the scene checks: each stage an error or a scene
            Ok(tree) => {
                if let Ok(imported) = wgtrace::scene::mitsuba::import(&tree, Path::new("")) {
                    let _ = wgtrace::load_scene_str(
                        &imported.toml,
                        Path::new("test.toml"),
                        &Default::default(),
                    );
                }
            }
        }
    }
}

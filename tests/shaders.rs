//! Shaders validate with naga, the preprocessor behaves, and every record shared with WGSL
//! has the layout naga gives the shader's struct. No GPU needed.

mod common;

use std::collections::BTreeSet;

use wgtrace::gpu::shader::{
    all_defines, kernel_shader, preprocess, scene_defines, scene_shader, trace_shader,
    used_bindings, validate, BAKED_PRIMITIVES_MAX, BAKED_RECORDS_MAX, ENTRY_SHADERS,
    FEATURE_DEFINES, SHADER_FILES,
};
use wgtrace::scene::format::{LightSampling, SamplerKind};
use wgtrace::scene::records::record_layouts;
use wgtrace::Overrides;

#[test]
fn every_entry_shader_validates_with_naga() {
    // with no feature define, with each alone, and with all of them
    let mut sets: Vec<BTreeSet<String>> = vec![BTreeSet::new()];
    sets.extend(
        FEATURE_DEFINES
            .iter()
            .map(|d| BTreeSet::from([d.to_string()])),
    );
    sets.push(FEATURE_DEFINES.iter().map(|d| d.to_string()).collect());
    for entry in ENTRY_SHADERS {
        for defines in &sets {
            let src = preprocess(entry, defines).unwrap();
            validate(entry, &src).unwrap_or_else(|e| panic!("{defines:?}: {e}"));
        }
    }
}

/// Every feature set that a scene in `scenes/` reaches, under each sampler and each
/// light-sampling strategy, with and without the BVH, validates with naga; and a trace
/// shader binds only the scene records it reads.
#[test]
fn every_feature_set_the_scenes_reach_validates_and_binds_only_what_it_uses() {
    let mut sets = BTreeSet::new();
    for path in common::scene_files() {
        for sampler in [
            SamplerKind::Random,
            SamplerKind::Jittered,
            SamplerKind::Hammersley,
            SamplerKind::Sobol,
        ] {
            for light_sampling in [
                LightSampling::Bsdf,
                LightSampling::Mixture,
                LightSampling::Mis,
            ] {
                for no_bvh in [false, true] {
                    let o = Overrides {
                        sampler: Some(sampler),
                        light_sampling: Some(light_sampling),
                        no_bvh,
                        ..Default::default()
                    };
                    let scene = wgtrace::load_scene(&path, &o).unwrap();
                    sets.insert(scene_defines(&scene));
                }
            }
        }
    }
    assert!(sets.len() > 100, "only {} feature sets", sets.len());
    let mut bound = BTreeSet::new();
    for defines in &sets {
        for entry in ENTRY_SHADERS {
            let src = preprocess(entry, defines).unwrap();
            validate(entry, &src).unwrap_or_else(|e| panic!("{defines:?}: {e}"));
        }
        let src = preprocess("trace", defines).unwrap();
        bound.insert(used_bindings("trace", &src, "main", 0).unwrap());
    }
    // binding numbers of shaders/shared/bindings.wgsl
    let (emitters, bvh, textures, texels) = (3, 5, 7, 8);
    let full = preprocess("trace", &all_defines()).unwrap();
    assert_eq!(
        used_bindings("trace", &full, "main", 0).unwrap(),
        (0..=8).collect::<Vec<u32>>()
    );
    let defines = |names: &[&str]| names.iter().map(|s| s.to_string()).collect();
    let cornell = defines(&[
        "HAS_BVH",
        "HAS_EMISSION",
        "HAS_LAMBERTIAN",
        "HAS_SOBOL",
        "HAS_SPHERE",
        "HAS_TRIANGLE",
    ]);
    let used = |d: &BTreeSet<String>| {
        used_bindings("trace", &preprocess("trace", d).unwrap(), "main", 0).unwrap()
    };
    // without light sampling or textures, their records are not bound
    for absent in [emitters, textures, texels] {
        assert!(!used(&cornell).contains(&absent), "{:?}", used(&cornell));
    }
    let mut no_bvh = cornell.clone();
    no_bvh.remove("HAS_BVH");
    no_bvh.insert("HAS_PRIMITIVE_LOOP".into());
    assert!(used(&cornell).contains(&bvh) && !used(&no_bvh).contains(&bvh));
    let mut mis = cornell.clone();
    mis.insert("HAS_MIS".into());
    assert!(used(&mis).contains(&emitters));
    // nothing emits: no path is traced, and only the parameters and the sums are bound
    assert_eq!(used(&BTreeSet::new()), vec![0, 4]);
    assert!(bound.len() > 4, "{bound:?}");
}

/// Every scene of `scenes/` small enough (no BVH, nothing transformed, at most
/// BAKED_PRIMITIVES_MAX primitives) gets its primitives written into its shader as
/// constants, and one of few materials or lights gets those; the shaders validate, and
/// every primitive's values read back bit for bit.
#[test]
fn small_scenes_get_their_primitives_as_constants_exactly() {
    let mut baked = Vec::new();
    for path in common::scene_files() {
        for (no_bvh, no_baked) in [(false, false), (true, false), (false, true)] {
            let o = Overrides {
                no_bvh,
                no_baked_records: no_baked,
                ..Default::default()
            };
            let scene = wgtrace::load_scene(&path, &o).unwrap();
            let spec = scene_shader(&scene);
            let expect = !no_baked
                && !scene.use_bvh
                && scene.primitives.len() <= BAKED_PRIMITIVES_MAX
                && scene
                    .primitives
                    .iter()
                    .all(|p| p.flags & wgtrace::scene::records::PRIM_FLAG_TRANSFORM == 0);
            assert_eq!(
                spec.defines.contains("BAKED_PRIMITIVES"),
                expect,
                "{}",
                path.display()
            );
            let few = |n: usize| !no_baked && (1..=BAKED_RECORDS_MAX).contains(&n);
            assert_eq!(
                spec.defines.contains("BAKED_MATERIALS"),
                few(scene.materials.len())
            );
            assert_eq!(
                spec.defines.contains("BAKED_EMITTERS"),
                few(scene.emitters.len())
            );
            assert_eq!(
                spec.defines.contains("SCENE_CODE"),
                !spec.scene_code.is_empty()
            );
            if spec.scene_code.is_empty() {
                continue;
            }
            let wgsl = trace_shader(&spec).unwrap();
            let module = validate("trace", &wgsl).unwrap();
            validate("kernel", &kernel_shader(&spec).unwrap()).unwrap();
            if !expect {
                continue;
            }
            // every nonzero component of every record is one of intersect_baked's literals
            let f = module
                .functions
                .iter()
                .find(|(_, f)| f.name.as_deref() == Some("intersect_baked"))
                .expect("intersect_baked")
                .1;
            let literals: BTreeSet<u32> = f
                .expressions
                .iter()
                .chain(module.global_expressions.iter())
                .filter_map(|(_, e)| match e {
                    naga::Expression::Literal(naga::Literal::F32(x)) => Some(x.to_bits()),
                    _ => None,
                })
                .collect();
            for p in &scene.primitives {
                for x in p.a.iter().chain(&p.b).chain(&p.c).filter(|&&x| x != 0.0) {
                    assert!(
                        literals.contains(&x.abs().to_bits()) || literals.contains(&x.to_bits()),
                        "{}: {x:?} not written exactly",
                        path.display()
                    );
                }
            }
            baked.push(path.file_name().unwrap().to_string_lossy().to_string());
        }
    }
    assert!(
        baked.iter().any(|n| n == "cornell.toml"),
        "baked: {baked:?}"
    );
}

#[test]
fn every_shader_file_is_embedded_and_imported() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut on_disk = Vec::new();
    for sub in ["", "shared"] {
        for e in std::fs::read_dir(dir.join(sub)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "wgsl") {
                let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
                on_disk.push(if sub.is_empty() {
                    stem
                } else {
                    format!("{sub}/{stem}")
                });
            }
        }
    }
    on_disk.sort();
    let mut embedded: Vec<String> = SHADER_FILES.iter().map(|(n, _)| n.to_string()).collect();
    embedded.sort();
    assert_eq!(
        on_disk, embedded,
        "shaders/ and gpu::shader::SHADER_FILES differ"
    );
    // The trace shader pulls in every shared file exactly once.
    let src = preprocess("trace", &BTreeSet::new()).unwrap();
    assert_eq!(src.matches("fn pcg4d(").count(), 1);
    assert_eq!(src.matches("struct Primitive {").count(), 1);
    assert!(!src.contains("#import"));
}

#[test]
fn preprocessor_selects_branches_imports_once_and_reports_errors() {
    use wgtrace::gpu::shader::preprocess_files;
    let files = [
        (
            "main",
            "#import a\n#import b\n#if FAST\nfast\n#ifndef WIDE\nnarrow\n#endif\n#else\nslow\n#import c\n#endif\nend",
        ),
        ("a", "#import b\nA"),
        ("b", "B"),
        ("c", "C"),
    ];
    let defs = |names: &[&str]| names.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>();
    let lines = |d: &[&str]| preprocess_files("main", &defs(d), &files).unwrap();
    assert_eq!(lines(&[]), "B\nA\nslow\nC\nend\n");
    assert_eq!(lines(&["FAST"]), "B\nA\nfast\nnarrow\nend\n");
    assert_eq!(lines(&["FAST", "WIDE"]), "B\nA\nfast\nend\n");

    let bad = |src: &'static str| {
        preprocess_files("m", &defs(&[]), &[("m", src)])
            .unwrap_err()
            .to_string()
    };
    assert!(bad("#if X\nx").contains("#if without #endif"));
    assert!(bad("#endif").contains("m:1: #endif without #if"));
    assert!(bad("x\n#import nope").contains("m:2: #import of unknown file nope"));
    let err = preprocess("no/such/file", &defs(&[])).unwrap_err();
    assert!(
        err.to_string()
            .contains("no shader file named no/such/file"),
        "{err}"
    );
}

/// Finds the struct named `name` in a naga module and returns (size, [(member, offset)]).
fn naga_struct(module: &naga::Module, name: &str) -> Option<(u32, Vec<(String, u32)>)> {
    module.types.iter().find_map(|(_, ty)| {
        if ty.name.as_deref() != Some(name) {
            return None;
        }
        match &ty.inner {
            naga::TypeInner::Struct { members, span } => Some((
                *span,
                members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect(),
            )),
            _ => None,
        }
    })
}

#[test]
fn records_match_naga_layout_of_the_shader() {
    let modules: Vec<naga::Module> = ENTRY_SHADERS
        .iter()
        .map(|name| validate(name, &preprocess(name, &BTreeSet::new()).unwrap()).unwrap())
        .collect();
    for rec in record_layouts() {
        let (size, members) = modules
            .iter()
            .find_map(|m| naga_struct(m, rec.name))
            .unwrap_or_else(|| panic!("struct {} not found in any entry shader", rec.name));
        assert_eq!(rec.size as u32, size, "{}: size (Rust vs WGSL)", rec.name);
        let rust: Vec<(String, u32)> = rec
            .fields
            .iter()
            .map(|(n, o)| (n.to_string(), *o as u32))
            .collect();
        assert_eq!(
            rust, members,
            "{}: fields and offsets (Rust vs WGSL)",
            rec.name
        );
    }
}

/// Each UNIFORM_* define turns its record array into a uniform buffer of the fixed length
/// 65536 bytes / record size (the largest whole number of records in `UNIFORM_BYTES`),
/// alone and all together, in the trace and the kernel shaders; the scenes whose records
/// fit get them, and the full shader none.
#[test]
fn uniform_record_arrays_have_the_fixed_lengths_and_bindings() {
    use wgtrace::gpu::shader::{uniform_bindings, uniform_defines, UNIFORM_BYTES, UNIFORM_DEFINES};
    let features = all_defines();
    let mut all = features.clone();
    for &(name, binding) in UNIFORM_DEFINES {
        let mut one = features.clone();
        one.insert(name.to_string());
        all.insert(name.to_string());
        for entry in ENTRY_SHADERS {
            let wgsl = preprocess(entry, &one).unwrap();
            assert_eq!(
                uniform_bindings(entry, &wgsl).unwrap(),
                vec![binding],
                "{entry} {name}"
            );
            let module = validate(entry, &wgsl).unwrap();
            let var = module
                .global_variables
                .iter()
                .map(|(_, v)| v)
                .find(|v| {
                    v.binding
                        .as_ref()
                        .is_some_and(|b| b.group == 0 && b.binding == binding)
                })
                .unwrap();
            let naga::TypeInner::Array {
                base,
                size: naga::ArraySize::Constant(len),
                stride,
            } = module.types[var.ty].inner
            else {
                panic!("{name}: binding {binding} is not a fixed-size array");
            };
            let record = module.types[base].inner.size(module.to_ctx()) as u64;
            assert_eq!(stride as u64, record, "{name}");
            assert_eq!(
                len.get() as u64,
                UNIFORM_BYTES / record,
                "{name}: {len} records of {record} bytes"
            );
        }
    }
    let wgsl = preprocess("trace", &all).unwrap();
    assert_eq!(
        uniform_bindings("trace", &wgsl).unwrap(),
        vec![1, 2, 3, 5, 6, 7]
    );
    assert!(
        uniform_bindings("trace", &preprocess("trace", &features).unwrap())
            .unwrap()
            .is_empty()
    );
    // every scene in scenes/ fits, and its shader gets all its record arrays as uniforms
    let scene = wgtrace::load_scene(
        &common::repo_path("scenes/cornell.toml"),
        &Overrides::default(),
    )
    .unwrap();
    assert_eq!(uniform_defines(&scene).len(), UNIFORM_DEFINES.len());
    assert!(scene_defines(&scene).contains("UNIFORM_PRIMITIVES"));
    let full = Overrides {
        no_specialize: true,
        ..Default::default()
    };
    let scene = wgtrace::load_scene(&common::repo_path("scenes/cornell.toml"), &full).unwrap();
    assert!(!scene_defines(&scene)
        .iter()
        .any(|d| d.starts_with("UNIFORM_")));
}

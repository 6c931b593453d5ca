//! Shaders validate with naga, the preprocessor behaves, every record shared with WGSL
//! has the layout naga gives the shader's struct, every constant and binding the two
//! languages share has one value, and a plan binds exactly what its shader reads. No GPU
//! needed.

mod common;

use std::collections::{BTreeMap, BTreeSet};

use wgtrace::gpu::bindings::{Placement, Placements, Slot, UNIFORM_BYTES};
use wgtrace::gpu::codegen::shared_constants;
use wgtrace::gpu::kernel::KERNEL_IO;
use wgtrace::gpu::limits::DeviceFit;
use wgtrace::gpu::plan::{
    Feature, FeatureSet, GpuPlan, ShaderSpec, BAKED_PRIMITIVES_MAX, BAKED_RECORDS_MAX,
};
use wgtrace::gpu::shader::{shader_files, used_bindings, validate, ENTRY_SHADERS};
use wgtrace::scene::format::{LightSampling, SamplerKind};
use wgtrace::scene::materials::MaterialKind;
use wgtrace::scene::primitives::PrimitiveKind;
use wgtrace::scene::records::{
    record_layouts, SharedValue, BVH_STACK_LANES, BVH_STACK_SIZE, SHARED_CONSTANTS,
};
use wgtrace::scene::texels::MAX_BANKS;
use wgtrace::{Overrides, Tuning};

/// The assembled and validated module of `entry` for `spec`.
fn module(spec: &ShaderSpec, entry: &str) -> naga::Module {
    let wgsl = spec.wgsl(entry).unwrap();
    validate(entry, &wgsl).unwrap_or_else(|e| panic!("{spec:?}: {e}"))
}

/// The slots naga finds the trace entry point reading.
fn naga_slots(spec: &ShaderSpec) -> Vec<Slot> {
    let wgsl = spec.wgsl("trace").unwrap();
    used_bindings("trace", &wgsl, "main", 0)
        .unwrap()
        .into_iter()
        .map(|b| Slot::ALL[b as usize])
        .collect()
}

/// Placements with every record array in `placement`.
fn all_placed(placement: Placement) -> Placements {
    let mut p = Placements::default();
    for slot in Slot::RECORDS {
        p.set(slot, placement);
    }
    p
}

/// With no feature, each alone and all of them, with the records in storage and in
/// uniform buffers, both entry shaders validate and the trace shader binds what it reads.
#[test]
fn every_entry_shader_validates_and_binds_what_it_reads() {
    let mut sets: Vec<FeatureSet> = vec![FeatureSet::default(), FeatureSet::all()];
    sets.extend(Feature::all().map(|f| FeatureSet::default().with(f, true)));
    // each feature with emission, so that its code is traced
    sets.extend(Feature::all().map(|f| {
        FeatureSet::default()
            .with(f, true)
            .with(Feature::Emission, true)
    }));
    // the primitives and the BVH may also be textures
    let mut textured = Placements::default();
    textured.set(Slot::Primitives, Placement::Texture);
    textured.set(Slot::Bvh, Placement::Texture);
    for features in sets {
        for placements in [
            all_placed(Placement::Storage),
            all_placed(Placement::Uniform),
            textured,
        ] {
            // two texel banks: texel_load's switch
            let mut spec = ShaderSpec {
                features,
                placements,
                banks: 2,
                scene_code: String::new(),
                lane_stats: false,
                register_stack: false,
            };
            for entry in ENTRY_SHADERS {
                module(&spec, entry);
            }
            // --tune lane-stats's counts (subgroup operations) in the BVH walk too
            if features.contains(Feature::Bvh) {
                spec.lane_stats = true;
                for entry in ENTRY_SHADERS {
                    module(&spec, entry);
                }
                spec.lane_stats = false;
                // the walk's stack in registers (gpu::plan::REGISTER_STACK): an entry per
                // level of the deepest tree it serves, and the count
                spec.register_stack = true;
                for entry in ENTRY_SHADERS {
                    let m = module(&spec, entry);
                    if !features.contains(Feature::Instances) {
                        let (_, members) = naga_struct(&m, "WalkStack").expect("WalkStack");
                        let want = wgtrace::scene::records::BVH_REGISTER_STACK as usize + 1;
                        assert_eq!(members.len(), want, "{entry}");
                    }
                }
                spec.register_stack = false;
            }
            let named: Vec<Feature> = features.iter().collect();
            assert_eq!(spec.trace_slots(), naga_slots(&spec), "{named:?}");
        }
    }
}

/// Every combination of the features that decide which records are read (textures, the
/// image background, light sampling), with emission, binds what its shader reads.
#[test]
fn every_combination_of_texture_and_light_features_binds_what_it_reads() {
    let deciding = [
        Feature::Textures,
        Feature::ImageTexture,
        Feature::NoiseTexture,
        Feature::EnvMap,
        Feature::Mis,
        Feature::Mixture,
    ];
    for bits in 0..1u32 << deciding.len() {
        let features: FeatureSet = deciding
            .iter()
            .enumerate()
            .filter(|(i, _)| bits & (1 << i) != 0)
            .map(|(_, &f)| f)
            .chain([
                Feature::Emission,
                Feature::Primitive(PrimitiveKind::Triangle),
                Feature::Material(MaterialKind::Lambertian),
            ])
            .collect();
        let spec = ShaderSpec::of(features);
        assert_eq!(
            spec.trace_slots(),
            naga_slots(&spec),
            "{:?}",
            features.iter().collect::<Vec<_>>()
        );
    }
}

/// Every plan a scene in `scenes/` gets, under each sampler and each light-sampling
/// strategy, with and without the BVH and the records written in, validates with naga and
/// binds exactly the slots naga finds its trace shader reading.
#[test]
fn every_plan_the_scenes_reach_validates_and_binds_only_what_it_reads() {
    let mut specs = BTreeSet::new();
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
                for knobs in ["", "no-bvh", "no-baked-records"] {
                    let o = Overrides {
                        sampler: Some(sampler),
                        light_sampling: Some(light_sampling),
                        ..Default::default()
                    };
                    let scene = common::load_tuned(&path, &o, knobs);
                    let tuning = Tuning::parse(knobs).unwrap();
                    specs.insert(GpuPlan::new(&scene, &DeviceFit::portable(), &tuning).shader);
                }
            }
        }
    }
    assert!(specs.len() > 100, "only {} shader specs", specs.len());
    let mut bound = BTreeSet::new();
    for spec in &specs {
        for entry in ENTRY_SHADERS {
            module(spec, entry);
        }
        assert_eq!(spec.trace_slots(), naga_slots(spec), "{:?}", spec.features);
        bound.insert(spec.trace_slots());
    }
    assert!(bound.len() > 4, "{bound:?}");
    // the full shader reads everything (with every texel bank)
    let every_bank = ShaderSpec {
        banks: MAX_BANKS as u32,
        ..ShaderSpec::full()
    };
    assert_eq!(every_bank.trace_slots(), Slot::ALL.to_vec());
    // nothing emits: no path is traced, and only the parameters and the sums are bound
    assert_eq!(
        ShaderSpec::of(FeatureSet::default()).trace_slots(),
        vec![Slot::Params, Slot::Accum]
    );
    // without light sampling or textures their records are not bound; the BVH only with it
    let cornell: FeatureSet = [
        Feature::Bvh,
        Feature::Emission,
        Feature::Material(MaterialKind::Lambertian),
        Feature::Sobol,
        Feature::Primitive(PrimitiveKind::Sphere),
        Feature::Primitive(PrimitiveKind::Triangle),
    ]
    .into_iter()
    .collect();
    let slots = |f: FeatureSet| ShaderSpec::of(f).trace_slots();
    for absent in [
        Slot::Emitters,
        Slot::Textures,
        Slot::Tables,
        Slot::Texels(0),
    ] {
        assert!(!slots(cornell).contains(&absent));
    }
    let no_bvh: FeatureSet = cornell
        .iter()
        .filter(|&f| f != Feature::Bvh)
        .chain([Feature::PrimitiveLoop])
        .collect();
    assert!(slots(cornell).contains(&Slot::Bvh) && !slots(no_bvh).contains(&Slot::Bvh));
    assert!(slots(cornell.with(Feature::Mis, true)).contains(&Slot::Emitters));
}

/// Every scene of `scenes/` small enough (no BVH, nothing transformed, at most
/// BAKED_PRIMITIVES_MAX primitives) gets its primitives written into its shader as
/// constants, and one of few materials or lights gets those; the shaders validate, and
/// every primitive's values read back bit for bit.
#[test]
fn small_scenes_get_their_primitives_as_constants_exactly() {
    let mut baked = Vec::new();
    for path in common::scene_files() {
        for knobs in ["", "no-bvh", "no-baked-records"] {
            let scene = common::load_tuned(&path, &Overrides::default(), knobs);
            let tuning = Tuning::parse(knobs).unwrap();
            let spec = GpuPlan::new(&scene, &DeviceFit::portable(), &tuning).shader;
            let in_shader = |s: Slot| spec.placements.get(s) == Placement::Shader;
            let on = tuning.baked_records;
            let expect = on
                && !scene.use_bvh
                && scene.primitives.len() <= BAKED_PRIMITIVES_MAX
                && scene
                    .primitives
                    .iter()
                    .all(|p| p.flags & wgtrace::scene::records::PRIM_FLAG_TRANSFORM == 0);
            let name = path.display();
            assert_eq!(in_shader(Slot::Primitives), expect, "{name}");
            assert_eq!(
                spec.defines().contains("BAKED_PRIMITIVES"),
                expect,
                "{name}"
            );
            let few = |n: usize| on && (1..=BAKED_RECORDS_MAX).contains(&n);
            assert_eq!(in_shader(Slot::Materials), few(scene.materials.len()));
            assert_eq!(in_shader(Slot::Emitters), few(scene.emitters.len()));
            assert_eq!(
                spec.scene_code.is_empty(),
                ![Slot::Primitives, Slot::Materials, Slot::Emitters]
                    .into_iter()
                    .any(in_shader)
            );
            if spec.scene_code.is_empty() {
                continue;
            }
            let module = module(&spec, "trace");
            validate("kernel", &spec.wgsl("kernel").unwrap()).unwrap();
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
                        "{name}: {x:?} not written exactly"
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
    for sub in ["", "shared", "materials", "primitives"] {
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
    let mut embedded: Vec<String> = shader_files().iter().map(|(n, _)| n.to_string()).collect();
    embedded.sort();
    assert_eq!(
        on_disk, embedded,
        "shaders/ and gpu::shader::shader_files() differ"
    );
    // The trace shader pulls in every shared file exactly once.
    let src = ShaderSpec::default().wgsl("trace").unwrap();
    assert_eq!(src.matches("fn pcg4d(").count(), 1);
    assert_eq!(src.matches("struct Primitive {").count(), 1);
    assert_eq!(src.matches("const NO_HIT:").count(), 1);
    assert!(!src.contains("#import"));
}

#[test]
fn preprocessor_selects_branches_imports_once_and_reports_errors() {
    use wgtrace::gpu::shader::{assemble, preprocess_files, Defines};
    let files = [
        (
            "main",
            "#import a\n#import b\n#if FAST\nfast\n#ifndef WIDE\nnarrow\n#endif\n#else\nslow\n#import c\n#endif\nend",
        ),
        ("a", "#import b\nA"),
        ("b", "B"),
        ("c", "C"),
    ];
    let defs = |names: &[&'static str]| names.iter().copied().collect::<BTreeSet<&str>>();
    let known = defs(&["FAST", "WIDE", "X"]);
    let lines = |d: &[&'static str]| {
        let set = defs(d);
        let d = Defines {
            known: &known,
            set: &set,
        };
        preprocess_files("main", d, &files).unwrap()
    };
    assert_eq!(lines(&[]), "B\nA\nslow\nC\nend\n");
    assert_eq!(lines(&["FAST"]), "B\nA\nfast\nnarrow\nend\n");
    assert_eq!(lines(&["FAST", "WIDE"]), "B\nA\nfast\nend\n");

    let none = defs(&[]);
    let nothing = Defines {
        known: &known,
        set: &none,
    };
    let bad = |src: &'static str| {
        preprocess_files("m", nothing, &[("m", src)])
            .unwrap_err()
            .to_string()
    };
    assert!(bad("#if X\nx").contains("#if without #endif"));
    assert!(bad("#endif").contains("m:1: #endif without #if"));
    assert!(bad("x\n#import nope").contains("m:2: #import of unknown file nope"));
    // a misspelled name is refused, not taken for an absent feature
    let e = bad("x\n#ifdef FAAST\ny\n#endif");
    assert!(
        e.contains("m:2: #ifdef FAAST: no such define; did you mean FAST?"),
        "{e}"
    );
    let unknown_set = defs(&["SLOW"]);
    let e = preprocess_files(
        "main",
        Defines {
            known: &known,
            set: &unknown_set,
        },
        &files,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("SLOW is defined but not a known name"), "{e}");
    let err = assemble("no/such/file", nothing, &[]).unwrap_err();
    assert!(
        err.to_string()
            .contains("no shader file named no/such/file"),
        "{err}"
    );
    // the shaders need the generated files
    let err = assemble("trace", nothing, &[]).unwrap_err().to_string();
    assert!(err.contains("#import of unknown file generated/"), "{err}");
}

/// Every `#if` of every shader file names a define the plan knows
/// (`ShaderSpec::known_defines`): the preprocessor refuses any other, so a misspelled
/// feature cannot leave its code out unnoticed.
#[test]
fn every_shader_directive_names_a_known_define() {
    let known = ShaderSpec::known_defines();
    let mut named = 0;
    for (name, src) in shader_files() {
        for (i, line) in src.lines().enumerate() {
            let mut words = line.split_whitespace();
            if let Some("#if" | "#ifdef" | "#ifndef") = words.next() {
                let flag = words.next().unwrap_or("");
                assert!(
                    known.contains(flag),
                    "shaders/{name}.wgsl:{}: {flag} is no define",
                    i + 1
                );
                named += 1;
            }
        }
    }
    assert!(named > 50, "{named} directives");
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
        .map(|name| module(&ShaderSpec::default(), name))
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

/// The constants the two languages share have one value: naga's module of each entry
/// shader holds exactly `SHARED_CONSTANTS` and the material tags of the type list, by
/// name, type and value (the WGSL gets them written from those), and no shader file
/// declares a constant of its own.
#[test]
fn shared_constants_have_one_value_in_both_languages() {
    for entry in ENTRY_SHADERS {
        let m = module(&ShaderSpec::full(), entry);
        let in_wgsl: BTreeMap<String, SharedValue> = m
            .constants
            .iter()
            .map(|(_, c)| {
                let value = match m.global_expressions[c.init] {
                    naga::Expression::Literal(naga::Literal::U32(v)) => SharedValue::U32(v),
                    naga::Expression::Literal(naga::Literal::F32(v)) => SharedValue::F32(v),
                    ref e => panic!("{:?} is not a u32 or f32 literal: {e:?}", c.name),
                };
                (c.name.clone().unwrap_or_default(), value)
            })
            .collect();
        // the shared constants and the material tags (gpu::codegen::shared_constants)
        let in_rust: BTreeMap<String, SharedValue> = shared_constants().into_iter().collect();
        assert!(in_rust.len() > SHARED_CONSTANTS.len());
        assert_eq!(in_wgsl.len(), in_rust.len(), "{entry}: {in_wgsl:?}");
        for (name, v) in &in_rust {
            let w = in_wgsl
                .get(name)
                .unwrap_or_else(|| panic!("{entry}: no {name}"));
            // compared by bits: FAR is f32::MAX, not a rounded neighbour
            let bits = |v: &SharedValue| match *v {
                SharedValue::U32(x) => (0, x),
                SharedValue::F32(x) => (1, x.to_bits()),
            };
            assert_eq!(bits(w), bits(v), "{entry}: {name}");
        }
    }
    for (name, src) in shader_files() {
        for (i, line) in src.lines().enumerate() {
            assert!(
                !line.trim_start().starts_with("const "),
                "shaders/{name}.wgsl:{}: a constant belongs in SHARED_CONSTANTS \
                 (src/scene/records.rs): {line}",
                i + 1
            );
        }
    }
}

/// Every binding has one number: naga's module holds each slot's variable, by the name
/// `Slot::name` gives, at `Slot::binding` of group 0, and the kernel's inputs and outputs
/// at `KERNEL_IO` of group 1.
#[test]
fn bindings_have_one_number_in_both_languages() {
    let m = module(&ShaderSpec::full(), "kernel");
    let globals: BTreeMap<String, (u32, u32)> = m
        .global_variables
        .iter()
        .filter_map(|(_, v)| {
            let b = v.binding.as_ref()?;
            Some((v.name.clone()?, (b.group, b.binding)))
        })
        .collect();
    for slot in Slot::ALL {
        assert_eq!(
            globals.get(slot.name()),
            Some(&(0, slot.binding())),
            "{slot:?}"
        );
    }
    for (name, binding) in KERNEL_IO {
        assert_eq!(globals.get(name), Some(&(1, binding)), "{name}");
    }
    assert_eq!(
        globals.len(),
        Slot::ALL.len() + KERNEL_IO.len(),
        "{globals:?}"
    );
    let numbers: BTreeSet<u32> = Slot::ALL.iter().map(|s| s.binding()).collect();
    assert_eq!(numbers.len(), Slot::ALL.len());
}

/// A record array placed in a uniform buffer has the fixed length 65536 bytes / record
/// size (the largest whole number of records in `UNIFORM_BYTES`), alone and all together,
/// in the trace and the kernel shaders; the scenes whose records fit get them, and the
/// full shader none.
#[test]
fn uniform_record_arrays_have_the_fixed_lengths_and_bindings() {
    let uniform_bindings = |m: &naga::Module| -> Vec<u32> {
        let mut v: Vec<u32> = m
            .global_variables
            .iter()
            .filter(|(_, v)| v.space == naga::AddressSpace::Uniform)
            .filter_map(|(_, v)| v.binding.as_ref())
            .filter(|b| b.group == 0 && b.binding != 0)
            .map(|b| b.binding)
            .collect();
        v.sort_unstable();
        v
    };
    for slot in Slot::RECORDS {
        let mut spec = ShaderSpec::full();
        spec.placements.set(slot, Placement::Uniform);
        for entry in ENTRY_SHADERS {
            let m = module(&spec, entry);
            assert_eq!(
                uniform_bindings(&m),
                vec![slot.binding()],
                "{entry} {slot:?}"
            );
            let var = m
                .global_variables
                .iter()
                .map(|(_, v)| v)
                .find(|v| {
                    v.binding
                        .as_ref()
                        .is_some_and(|b| b.group == 0 && b.binding == slot.binding())
                })
                .unwrap();
            let naga::TypeInner::Array {
                base,
                size: naga::ArraySize::Constant(len),
                stride,
            } = m.types[var.ty].inner
            else {
                panic!("{slot:?} is not a fixed-size array");
            };
            let record = m.types[base].inner.size(m.to_ctx()) as u64;
            assert_eq!(stride as u64, record, "{slot:?}");
            assert_eq!(
                len.get() as u64,
                UNIFORM_BYTES / record,
                "{slot:?}: {len} records of {record} bytes"
            );
        }
    }
    let mut all = ShaderSpec::full();
    all.placements = all_placed(Placement::Uniform);
    assert_eq!(
        uniform_bindings(&module(&all, "trace")),
        vec![1, 2, 3, 5, 6, 7]
    );
    assert!(uniform_bindings(&module(&ShaderSpec::full(), "trace")).is_empty());
    // the Cornell box fits: every record array not written into its shader is uniform
    let cornell = common::repo_path("scenes/cornell.toml");
    let scene = wgtrace::load_scene(&cornell, &Overrides::default()).unwrap();
    let plan = GpuPlan::new(&scene, &DeviceFit::portable(), &Tuning::default());
    for slot in Slot::RECORDS {
        assert_ne!(
            plan.shader.placements.get(slot),
            Placement::Storage,
            "{slot:?}"
        );
    }
    // not on a device that cannot bind that many uniform buffers
    let small = DeviceFit {
        uniform_records: false,
        ..DeviceFit::portable()
    };
    let plan = GpuPlan::new(&scene, &small, &Tuning::default());
    assert!(Slot::RECORDS
        .iter()
        .all(|&s| plan.shader.placements.get(s) != Placement::Uniform));
    // nor in the full shader
    let full = GpuPlan::new(
        &scene,
        &DeviceFit::portable(),
        &Tuning::parse("no-specialize").unwrap(),
    );
    // (with the scene's texel banks)
    let full_for = ShaderSpec {
        banks: plan.shader.banks,
        ..ShaderSpec::full_for(plan.shader.features)
    };
    assert_eq!(full.shader, full_for);
    // the full shader leaves out alpha and normal maps for a scene without them, and
    // holds them for one with them
    assert!(ShaderSpec::OPTIONAL_IN_FULL
        .iter()
        .all(|&f| !full.shader.features.contains(f) && ShaderSpec::full().features.contains(f)));
    let all = ShaderSpec::full_for(ShaderSpec::full().features);
    assert_eq!(all, ShaderSpec::full());
}

/// The plan follows the tuning: the sample group, the full shader, the records.
#[test]
fn the_plan_follows_the_tuning() {
    let cornell = common::repo_path("scenes/cornell.toml");
    let scene = wgtrace::load_scene(&cornell, &Overrides::default()).unwrap();
    let fit = DeviceFit::portable();
    let plan = |knobs: &str| GpuPlan::new(&scene, &fit, &Tuning::parse(knobs).unwrap());
    assert_eq!(plan("").sample_group, wgtrace::gpu::plan::SAMPLE_GROUP);
    assert_eq!(plan("no-sample-groups").sample_group, 1);
    assert!(plan("no-baked-records").shader.scene_code.is_empty());
    let storage = plan("no-uniform-records,no-baked-records,no-texture-records");
    assert!(Slot::RECORDS
        .iter()
        .all(|&s| storage.shader.placements.get(s) == Placement::Storage));
    // the primitives and the BVH too large for a uniform buffer go to textures
    let textured = plan("no-uniform-records,no-baked-records")
        .shader
        .placements;
    assert_eq!(textured.get(Slot::Primitives), Placement::Texture);
    assert_eq!(textured.get(Slot::Materials), Placement::Storage);
    assert!(Tuning::parse("no-such-knob")
        .unwrap_err()
        .contains("no-russian-roulette"));
    assert!(Tuning::parse("bvh,no-bvh").is_err());

    // the BVH walk's stack in registers for a tree of depth at most BVH_REGISTER_STACK
    // without instances, in workgroup memory otherwise or when turned off
    use wgtrace::gpu::plan::REGISTER_STACK;
    use wgtrace::scene::records::BVH_REGISTER_STACK;
    let mesh = common::repo_path("scenes/mesh.toml");
    let mut scene = wgtrace::load_scene(&mesh, &Overrides::default()).unwrap();
    assert!(scene.use_bvh && scene.bvh_depth <= BVH_REGISTER_STACK);
    let defines = |scene: &wgtrace::scene::flat::FlatScene, knobs: &str| {
        GpuPlan::new(scene, &fit, &Tuning::parse(knobs).unwrap())
            .shader
            .defines()
    };
    assert!(defines(&scene, "").contains(REGISTER_STACK));
    assert!(!defines(&scene, "no-register-stack").contains(REGISTER_STACK));
    scene.bvh_depth = BVH_REGISTER_STACK + 1;
    assert!(!defines(&scene, "").contains(REGISTER_STACK));
    let head = "[camera]\nlook_from = [0, 1, 7]\nlook_at = [0, 0, 0]\n[background]\n\
        color = [1, 1, 1]\n[materials]\nm = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n";
    let (instanced, _) = common::instances::instanced_and_expanded(head);
    let scene = common::scene_from_file_str(&instanced, "scenes/instances-test.toml");
    assert!(scene.use_bvh && scene.bvh_depth <= BVH_REGISTER_STACK);
    assert!(!defines(&scene, "").contains(REGISTER_STACK));
}

/// Every entry point of the entry shaders runs BVH_STACK_LANES invocations per workgroup,
/// one per column of the workgroup-memory traversal stack, and that stack fits the
/// workgroup memory every device has (WebGPU's default limit).
#[test]
fn traversal_stacks_fit_workgroup_memory_one_column_per_invocation() {
    let (lanes, depth) = (BVH_STACK_LANES, BVH_STACK_SIZE);
    let spec = ShaderSpec {
        features: FeatureSet::default()
            .with(Feature::Bvh, true)
            .with(Feature::Emission, true),
        placements: Placements::default(),
        banks: 1,
        scene_code: String::new(),
        lane_stats: false,
        register_stack: false,
    };
    for entry in ENTRY_SHADERS {
        let module = module(&spec, entry);
        assert!(!module.entry_points.is_empty());
        for ep in &module.entry_points {
            let [x, y, z] = ep.workgroup_size;
            assert_eq!(x * y * z, lanes, "{entry}: {}", ep.name);
        }
        let (_, var) = module
            .global_variables
            .iter()
            .find(|(_, v)| v.name.as_deref() == Some("bvh_stack"))
            .unwrap_or_else(|| panic!("{entry}: no bvh_stack"));
        assert_eq!(var.space, naga::AddressSpace::WorkGroup);
        let bytes = module.types[var.ty].inner.size(module.to_ctx());
        assert_eq!(bytes, depth * lanes * 8, "{entry}");
        assert!(bytes <= wgpu::Limits::default().max_compute_workgroup_storage_size);
    }
}

/// Every material's view, with the surface view every material has, names places the
/// record has, each of the field's type (a colour the xyz of a vec4, a scalar one lane of
/// one, a texture a u32), and no two of its fields share a component of the record.
#[test]
fn material_views_name_real_places_without_overlap() {
    use wgtrace::scene::materials::common::{FieldKind, Surface};
    use wgtrace::scene::records::{FieldValue, Material, SharedRecord};
    let zero: Material = bytemuck::Zeroable::zeroed();
    let places = zero.fields();
    for &kind in MaterialKind::ALL {
        let mut used = BTreeSet::new();
        for f in Surface::VIEW.fields.iter().chain(kind.view().fields) {
            let (_, value) = places
                .iter()
                .find(|(n, _)| *n == f.place)
                .unwrap_or_else(|| {
                    panic!("{}: {} names no place {}", kind.name(), f.name, f.place)
                });
            let fits = match (value, f.kind, f.lane) {
                (FieldValue::Vec4(_), FieldKind::Rgb, None) => true,
                (FieldValue::Vec4(_), FieldKind::F32, Some(l)) => {
                    "xyzw".contains(l) && l.len() == 1
                }
                (FieldValue::U32(_), FieldKind::U32, None) => true,
                _ => false,
            };
            assert!(
                fits,
                "{}: {} ({:?}) does not fit {}",
                kind.name(),
                f.name,
                f.kind,
                f.place
            );
            for c in f.components() {
                assert!(
                    used.insert(c),
                    "{}: {} shares {c:?} with another field",
                    kind.name(),
                    f.name
                );
            }
        }
    }
}

//! Shader sources and the small preprocessor that assembles them.
//!
//! Directives (each alone on its line):
//! - `#import shared/name` pulls in `shaders/shared/name.wgsl`, once per assembled shader;
//! - `#if NAME` / `#ifdef NAME`, `#ifndef NAME`, `#else`, `#endif` keep or drop lines by
//!   whether `NAME` is in the set of defines (they nest).

use std::collections::BTreeSet;

/// Every shader file, by the name `#import` uses; embedded so the binary runs from anywhere.
pub const SHADER_FILES: &[(&str, &str)] = &[
    ("trace", include_str!("../../shaders/trace.wgsl")),
    ("kernel", include_str!("../../shaders/kernel.wgsl")),
    (
        "shared/bindings",
        include_str!("../../shaders/shared/bindings.wgsl"),
    ),
    (
        "shared/intersect",
        include_str!("../../shaders/shared/intersect.wgsl"),
    ),
    (
        "shared/lights",
        include_str!("../../shaders/shared/lights.wgsl"),
    ),
    (
        "shared/materials",
        include_str!("../../shaders/shared/materials.wgsl"),
    ),
    ("shared/rng", include_str!("../../shaders/shared/rng.wgsl")),
    (
        "shared/samplers",
        include_str!("../../shaders/shared/samplers.wgsl"),
    ),
    (
        "shared/sampling",
        include_str!("../../shaders/shared/sampling.wgsl"),
    ),
    (
        "shared/textures",
        include_str!("../../shaders/shared/textures.wgsl"),
    ),
    (
        "shared/types",
        include_str!("../../shaders/shared/types.wgsl"),
    ),
];

/// Entry-point files: each is assembled into one shader module.
pub const ENTRY_SHADERS: &[&str] = &["trace", "kernel"];

#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    #[error("shader {file}:{line}: {message}")]
    Preprocess {
        file: String,
        line: usize,
        message: String,
    },
    #[error("shader {name} does not validate:\n{message}")]
    Invalid { name: String, message: String },
}

/// Assembles shader `entry` with its imports, keeping the `#if` branches selected by
/// `defines`.
pub fn preprocess(entry: &str, defines: &BTreeSet<String>) -> Result<String, ShaderError> {
    preprocess_files(entry, defines, SHADER_FILES)
}

/// [`preprocess`] over a given set of `(name, source)` files.
pub fn preprocess_files(
    entry: &str,
    defines: &BTreeSet<String>,
    files: &[(&str, &str)],
) -> Result<String, ShaderError> {
    let mut out = String::new();
    let mut imported = BTreeSet::new();
    imported.insert(entry.to_string());
    expand(entry, defines, files, &mut imported, &mut out)?;
    Ok(out)
}

fn expand(
    name: &str,
    defines: &BTreeSet<String>,
    files: &[(&str, &str)],
    imported: &mut BTreeSet<String>,
    out: &mut String,
) -> Result<(), ShaderError> {
    let source = |name: &str| files.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
    let err = |line: usize, message: String| ShaderError::Preprocess {
        file: name.to_string(),
        line,
        message,
    };
    let src = source(name).ok_or_else(|| err(0, format!("no shader file named {name}")))?;
    // One entry per open #if: (this branch is active, the enclosing context is active).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let active = |stack: &[(bool, bool)]| stack.last().is_none_or(|&(a, _)| a);
    for (i, line) in src.lines().enumerate() {
        let lineno = i + 1;
        let trimmed = line.trim();
        let mut words = trimmed.split_whitespace();
        match words.next() {
            Some(d @ ("#if" | "#ifdef" | "#ifndef")) => {
                let flag = words
                    .next()
                    .ok_or_else(|| err(lineno, format!("{d} needs a name")))?;
                let outer = active(&stack);
                let on = defines.contains(flag) != (d == "#ifndef");
                stack.push((outer && on, outer));
            }
            Some("#else") => {
                let (a, outer) = stack
                    .pop()
                    .ok_or_else(|| err(lineno, "#else without #if".into()))?;
                stack.push((outer && !a, outer));
            }
            Some("#endif") => {
                stack
                    .pop()
                    .ok_or_else(|| err(lineno, "#endif without #if".into()))?;
            }
            Some("#import") if active(&stack) => {
                let dep = words
                    .next()
                    .ok_or_else(|| err(lineno, "#import needs a name".into()))?;
                if source(dep).is_none() {
                    return Err(err(lineno, format!("#import of unknown file {dep}")));
                }
                if imported.insert(dep.to_string()) {
                    expand(dep, defines, files, imported, out)?;
                }
            }
            _ if active(&stack) => {
                out.push_str(line);
                out.push('\n');
            }
            _ => {}
        }
    }
    if !stack.is_empty() {
        return Err(err(src.lines().count(), "#if without #endif".into()));
    }
    Ok(())
}

/// Parses and validates assembled WGSL with naga, as wgpu will.
pub fn validate(name: &str, wgsl: &str) -> Result<naga::Module, ShaderError> {
    Ok(validate_with_info(name, wgsl)?.0)
}

fn validate_with_info(
    name: &str,
    wgsl: &str,
) -> Result<(naga::Module, naga::valid::ModuleInfo), ShaderError> {
    let invalid = |message: String| ShaderError::Invalid {
        name: name.to_string(),
        message,
    };
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| invalid(e.emit_to_string(wgsl)))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| invalid(e.emit_to_string(wgsl)))?;
    Ok((module, info))
}

/// The bindings of `group` that entry point `entry` of the assembled shader uses (reads,
/// writes or queries), in increasing order: what its pipeline layout must hold. A
/// resource declared but reached only from code the defines left out is not among them.
pub fn used_bindings(
    name: &str,
    wgsl: &str,
    entry: &str,
    group: u32,
) -> Result<Vec<u32>, ShaderError> {
    let (module, info) = validate_with_info(name, wgsl)?;
    let index = module
        .entry_points
        .iter()
        .position(|e| e.name == entry)
        .ok_or_else(|| ShaderError::Invalid {
            name: name.to_string(),
            message: format!("no entry point {entry}"),
        })?;
    let uses = info.get_entry_point(index);
    let mut bindings: Vec<u32> = module
        .global_variables
        .iter()
        .filter(|&(handle, _)| !uses[handle].is_empty())
        .filter_map(|(_, var)| var.binding.as_ref())
        .filter(|b| b.group == group)
        .map(|b| b.binding)
        .collect();
    bindings.sort_unstable();
    Ok(bindings)
}

/// What a shader is assembled from: its defines, and the code generated for one scene
/// ([`scene_code`]), which `#import generated/scene` pulls in; empty for a shader that
/// serves every scene of its feature set.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ShaderSpec {
    pub defines: BTreeSet<String>,
    pub scene_code: String,
}

impl From<BTreeSet<String>> for ShaderSpec {
    fn from(defines: BTreeSet<String>) -> Self {
        ShaderSpec {
            defines,
            scene_code: String::new(),
        }
    }
}

/// The name `#import` gives the generated scene code of a [`ShaderSpec`].
pub const SCENE_CODE_FILE: &str = "generated/scene";

/// Assembles shader `entry` for `spec`: its defines, with its scene code importable.
pub fn assemble(entry: &str, spec: &ShaderSpec) -> Result<String, ShaderError> {
    let mut files = SHADER_FILES.to_vec();
    files.push((SCENE_CODE_FILE, spec.scene_code.as_str()));
    preprocess_files(entry, &spec.defines, &files)
}

/// The trace shader for a scene.
pub fn trace_shader(spec: &ShaderSpec) -> Result<String, ShaderError> {
    assemble("trace", spec)
}

/// The intersection kernel used by tests (`shaders/kernel.wgsl`), assembled.
pub fn kernel_shader(spec: &ShaderSpec) -> Result<String, ShaderError> {
    assemble("kernel", spec)
}

/// The most primitives a scene's shader holds as constants ([`baked_primitives`]).
pub const BAKED_PRIMITIVES_MAX: usize = 32;

/// The most materials, and the most lights, a scene's shader holds as constants
/// ([`baked_records`]): each look-up is a chain of selects over all of them.
pub const BAKED_RECORDS_MAX: usize = 8;

/// A WGSL f32 literal that parses back to exactly `x` (naga reads a literal with the `f`
/// suffix as an f32; Rust's shortest round-trip form is exact).
fn wgsl_f32(x: f32) -> String {
    format!("{x:?}f")
}

fn wgsl_vec4(v: [f32; 4]) -> String {
    let c: Vec<String> = v.iter().map(|&x| wgsl_f32(x)).collect();
    format!("vec4<f32>({})", c.join(", "))
}

/// Whether [`baked_primitives`] writes the scene's primitives into its shader.
pub fn bakes_primitives(scene: &crate::scene::FlatScene) -> bool {
    use crate::scene::records as r;
    let prims = &scene.primitives;
    scene.specialize
        && scene.baked_records
        && !scene.use_bvh
        && !prims.is_empty()
        && prims.len() <= BAKED_PRIMITIVES_MAX
        && prims.iter().all(|p| p.flags & r::PRIM_FLAG_TRANSFORM == 0)
}

/// The code generated for a small scene (`BAKED_PRIMITIVES`): `intersect_baked`, the
/// closest-hit search with every primitive's record written into the shader as a
/// constant, tested in index order as the CPU's loop does. llvmpipe loads a record from a
/// uniform buffer with a gather per component even at a constant index; a constant costs
/// nothing (1.9x on the Cornell box in alternating runs; docs/performance.md has all the
/// records written in as one row). Also `occluded_baked`, the any-hit search of shadow
/// rays (no closest hit to keep: 2% fewer instructions in the Cornell box's bounce loop),
/// and `primitive_record`, for `surface_at`. None when the
/// scene has a BVH, a transformed primitive, more than [`BAKED_PRIMITIVES_MAX`]
/// primitives, is not specialized, or was loaded with `--no-baked-records`.
pub fn baked_primitives(scene: &crate::scene::FlatScene) -> Option<String> {
    if !bakes_primitives(scene) {
        return None;
    }
    let prims = &scene.primitives;
    let mut code = format!(
        "// The scene's {} primitives as constants (gpu::shader::baked_primitives).\n\
         fn intersect_baked(ray: Ray, t_max: f32) -> Candidate {{\n    \
         var best = Candidate(t_max, NO_HIT, 0.0, 0.0);\n",
        prims.len()
    );
    let records: Vec<String> = prims
        .iter()
        .map(|p| {
            format!(
                "Primitive({}u, {}u, {}u, {}u, {}, {}, {})",
                p.tag,
                p.material,
                p.flags,
                p.data,
                wgsl_vec4(p.a),
                wgsl_vec4(p.b),
                wgsl_vec4(p.c)
            )
        })
        .collect();
    for (i, (p, record)) in prims.iter().zip(&records).enumerate() {
        code += &format!(
            "    best = closer_hit(best, {i}u, intersect_local({record}, {}u, ray, best.t));\n",
            p.tag
        );
    }
    code += "    return best;\n}\n\
             // Whether any primitive lies along the ray before t_max (a shadow ray).\n\
             fn occluded_baked(ray: Ray, t_max: f32) -> bool {\n    var t = FAR;\n";
    for (p, record) in prims.iter().zip(&records) {
        code += &format!(
            "    t = min(t, intersect_local({record}, {}u, ray, t_max).x);\n",
            p.tag
        );
    }
    code += "    return t < FAR;\n}\n";
    code += &record_lookup("primitive_record", "Primitive", &records);
    Some(code)
}

/// A record look-up as generated WGSL: `fn name(i: u32) -> ty` that starts from the first
/// record and replaces it with record k where i == k (llvmpipe turns each into selects).
fn record_lookup(name: &str, ty: &str, records: &[String]) -> String {
    let mut code = format!(
        "fn {name}(i: u32) -> {ty} {{\n    var r = {};\n",
        records[0]
    );
    for (k, rec) in records.iter().enumerate().skip(1) {
        code += &format!("    if (i == {k}u) {{\n        r = {rec};\n    }}\n");
    }
    code + "    return r;\n}\n"
}

/// The code generated for a scene of few materials and lights (`BAKED_MATERIALS`,
/// `BAKED_EMITTERS`): `material_record` and `emitter_record` pick a record among constants
/// instead of gathering it from a uniform buffer lane by lane. At most
/// [`BAKED_RECORDS_MAX`] of each; a specialized shader only, and not with
/// `--no-baked-records`. On the Cornell box they made lavapipe 1.35x faster, and the
/// primitive records (`primitive_record`, for `surface_at`) 1.1x more.
pub fn baked_records(scene: &crate::scene::FlatScene) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    if !scene.specialize || !scene.baked_records {
        return out;
    }
    let fits = |n: usize| (1..=BAKED_RECORDS_MAX).contains(&n);
    if fits(scene.materials.len()) {
        let records: Vec<String> = scene
            .materials
            .iter()
            .map(|m| {
                format!(
                    "Material({}u, {}u, {}u, {}u, {}, {}, {}, {}, {}u, 0u, 0u, 0u)",
                    m.tag,
                    m.flags,
                    m.tex_albedo,
                    m.tex_emission,
                    wgsl_vec4(m.albedo),
                    wgsl_vec4(m.emission),
                    wgsl_vec4(m.params),
                    wgsl_vec4(m.extra),
                    m.tex_extra
                )
            })
            .collect();
        out.push((
            "BAKED_MATERIALS",
            record_lookup("material_record", "Material", &records),
        ));
    }
    if fits(scene.emitters.len()) {
        let records: Vec<String> = scene
            .emitters
            .iter()
            .map(|e| {
                format!(
                    "Emitter({}u, {}u, {}, {}, {}, {}, {}, {}, {}, 0u, 0u)",
                    e.primitive,
                    e.kind,
                    wgsl_f32(e.prob),
                    wgsl_f32(e.cdf),
                    wgsl_vec4(e.a),
                    wgsl_vec4(e.b),
                    wgsl_vec4(e.c),
                    wgsl_f32(e.area),
                    wgsl_f32(e.power)
                )
            })
            .collect();
        // choose_light's binary search as a count of the running sums at or below u: the
        // same index, as the sums never decrease (1.7% fewer instructions in the Cornell
        // box's bounce loop)
        let mut code = record_lookup("emitter_record", "Emitter", &records);
        code += "fn choose_light_baked(u: f32) -> u32 {\n    var i = 0u;\n";
        for e in &scene.emitters[..scene.emitters.len() - 1] {
            code += &format!("    i += select(0u, 1u, u >= {});\n", wgsl_f32(e.cdf));
        }
        out.push(("BAKED_EMITTERS", code + "    return i;\n}\n"));
    }
    out
}

/// The shader spec of a scene: [`scene_defines`], plus the records written in as
/// constants where [`baked_primitives`] and [`baked_records`] give them, each with its
/// define, all under `SCENE_CODE` (which imports the generated file).
pub fn scene_shader(scene: &crate::scene::FlatScene) -> ShaderSpec {
    let mut spec = ShaderSpec::from(scene_defines(scene));
    let mut parts: Vec<(&str, String)> = baked_primitives(scene)
        .map(|code| ("BAKED_PRIMITIVES", code))
        .into_iter()
        .collect();
    parts.extend(baked_records(scene));
    for (define, code) in parts {
        spec.defines.insert(define.to_string());
        spec.scene_code += &code;
    }
    if !spec.scene_code.is_empty() {
        spec.defines.insert("SCENE_CODE".to_string());
    }
    spec
}

/// Every define a shader may be assembled with (the tests validate each alone, none and
/// all, and every set a scene in `scenes/` reaches). Each keeps the code of one feature:
/// a primitive type, object-space transforms, the BVH walk or the plain loop over
/// primitives, a material type, textures and each texture type, a pixel sampler (random
/// is always there), a light-sampling strategy (bsdf is always there), an image
/// background, and emission at all (without it no path is traced). The thin lens is always
/// there: a pinhole without it measured slower on llvmpipe (ARCHITECTURE.md, Known costs).
pub const FEATURE_DEFINES: &[&str] = &[
    "HAS_SPHERE",
    "HAS_TRIANGLE",
    "HAS_PLANE",
    "HAS_BOX",
    "HAS_CYLINDER",
    "HAS_DISK",
    "HAS_TRANSFORMS",
    "HAS_BVH",
    "HAS_PRIMITIVE_LOOP",
    "HAS_LAMBERTIAN",
    "HAS_METAL",
    "HAS_DIELECTRIC",
    "HAS_MICROFACET",
    "HAS_TEXTURES",
    "HAS_IMAGE_TEXTURE",
    "HAS_NOISE_TEXTURE",
    "HAS_CHECKER_TEXTURE",
    "HAS_JITTERED",
    "HAS_HAMMERSLEY",
    "HAS_SOBOL",
    "HAS_MIS",
    "HAS_MIXTURE",
    "HAS_ENV_MAP",
    "HAS_EMISSION",
];

/// Bytes of a read-only record array that is a uniform buffer: WebGPU's and lavapipe's
/// `maxUniformBufferBindingSize` (Vulkan promises 16 KiB; desktop GPUs give 64 KiB).
pub const UNIFORM_BYTES: u64 = 1 << 16;

/// Layout defines, not features: each makes one read-only record array a uniform buffer
/// of [`UNIFORM_BYTES`] instead of a storage buffer (`shaders/shared/bindings.wgsl`), with
/// its binding number. llvmpipe loads a storage buffer one lane and one 32-bit component
/// at a time, a uniform one with one gather per component: on the Cornell box the
/// uniform records alone made lavapipe 2.1x faster (docs/performance.md). The full shader
/// has none of them, as
/// it must hold scenes of any size.
pub const UNIFORM_DEFINES: &[(&str, u32)] = &[
    ("UNIFORM_PRIMITIVES", 1),
    ("UNIFORM_MATERIALS", 2),
    ("UNIFORM_EMITTERS", 3),
    ("UNIFORM_BVH", 5),
    ("UNIFORM_SHAPE_DATA", 6),
    ("UNIFORM_TEXTURES", 7),
];

/// The UNIFORM_* defines of the scene's record arrays that fit in [`UNIFORM_BYTES`].
pub fn uniform_defines(scene: &crate::scene::FlatScene) -> Vec<&'static str> {
    let bytes = |binding: u32| -> usize {
        match binding {
            1 => std::mem::size_of_val(&scene.primitives[..]),
            2 => std::mem::size_of_val(&scene.materials[..]),
            3 => std::mem::size_of_val(&scene.emitters[..]),
            5 => std::mem::size_of_val(&scene.bvh[..]),
            6 => std::mem::size_of_val(&scene.shape_data[..]),
            7 => std::mem::size_of_val(&scene.textures[..]),
            _ => unreachable!("binding {binding} has no UNIFORM_ define"),
        }
    };
    UNIFORM_DEFINES
        .iter()
        .filter(|&&(_, binding)| bytes(binding) as u64 <= UNIFORM_BYTES)
        .map(|&(name, _)| name)
        .collect()
}

/// `spec` without the UNIFORM_* defines when the device cannot bind them: uniform
/// buffers of [`UNIFORM_BYTES`], one per record array plus the parameters.
pub fn fit_to_limits(spec: &ShaderSpec, limits: &wgpu::Limits) -> ShaderSpec {
    let fits = limits.max_uniform_buffer_binding_size >= UNIFORM_BYTES
        && limits.max_uniform_buffers_per_shader_stage as usize > UNIFORM_DEFINES.len();
    ShaderSpec {
        defines: spec
            .defines
            .iter()
            .filter(|d| fits || !UNIFORM_DEFINES.iter().any(|(u, _)| u == d))
            .cloned()
            .collect(),
        scene_code: spec.scene_code.clone(),
    }
}

/// The group-0 bindings other than the parameters (binding 0) that the assembled shader
/// declares as uniform buffers.
pub fn uniform_bindings(name: &str, wgsl: &str) -> Result<Vec<u32>, ShaderError> {
    let module = validate(name, wgsl)?;
    let mut out: Vec<u32> = module
        .global_variables
        .iter()
        .filter(|(_, v)| v.space == naga::AddressSpace::Uniform)
        .filter_map(|(_, v)| v.binding.as_ref())
        .filter(|b| b.group == 0 && b.binding != 0)
        .map(|b| b.binding)
        .collect();
    out.sort_unstable();
    Ok(out)
}

/// Every feature define: the full shader (`--no-specialize`), which picks the sampler,
/// the light-sampling strategy and BVH or not at run time from `Params`.
pub fn all_defines() -> BTreeSet<String> {
    FEATURE_DEFINES.iter().map(|d| d.to_string()).collect()
}

/// Whether anything in the scene gives off light: an emitting material (a colour or an
/// emission texture) or a background that is not black.
pub fn scene_emits(scene: &crate::scene::FlatScene) -> bool {
    let bright = |c: &[f32]| c.iter().any(|&x| x > 0.0);
    scene
        .materials
        .iter()
        .any(|m| bright(&m.emission[..3]) || m.tex_emission != crate::scene::records::NO_TEXTURE)
        || bright(&scene.background)
        || scene.background_top.is_some_and(|t| bright(&t))
        || scene.env.is_some()
}

/// The defines a scene's shaders are assembled with: code for features the scene does not
/// use is left out (llvmpipe runs untaken branches and switch cases under a mask, so absent
/// code still costs time there), and record arrays that fit are uniform buffers
/// ([`UNIFORM_DEFINES`]). A scene flattened with `specialize` off gets every feature and
/// no uniform records.
pub fn scene_defines(scene: &crate::scene::FlatScene) -> BTreeSet<String> {
    use crate::scene::records as r;
    if !scene.specialize {
        return all_defines();
    }
    let mut defines = BTreeSet::new();
    let mut add = |on: bool, name: &str| {
        if on {
            defines.insert(name.to_string());
        }
    };
    let prim = |tag: u32| scene.primitives.iter().any(|p| p.tag == tag);
    let mat = |tag: u32| scene.materials.iter().any(|m| m.tag == tag);
    add(prim(r::PRIM_SPHERE), "HAS_SPHERE");
    add(prim(r::PRIM_TRIANGLE), "HAS_TRIANGLE");
    add(prim(r::PRIM_PLANE), "HAS_PLANE");
    add(prim(r::PRIM_BOX), "HAS_BOX");
    add(prim(r::PRIM_CYLINDER), "HAS_CYLINDER");
    add(prim(r::PRIM_DISK), "HAS_DISK");
    add(
        scene
            .primitives
            .iter()
            .any(|p| p.flags & r::PRIM_FLAG_TRANSFORM != 0),
        "HAS_TRANSFORMS",
    );
    let bounded = scene.primitives.len() > scene.num_unbounded as usize;
    add(bounded && scene.use_bvh, "HAS_BVH");
    add(bounded && !scene.use_bvh, "HAS_PRIMITIVE_LOOP");
    add(mat(r::MAT_LAMBERTIAN), "HAS_LAMBERTIAN");
    add(mat(r::MAT_METAL), "HAS_METAL");
    add(mat(r::MAT_DIELECTRIC), "HAS_DIELECTRIC");
    add(mat(r::MAT_MICROFACET), "HAS_MICROFACET");
    add(!scene.textures.is_empty(), "HAS_TEXTURES");
    let texture = |tag: u32| scene.textures.iter().any(|t| t.tag == tag);
    add(texture(r::TEX_IMAGE), "HAS_IMAGE_TEXTURE");
    add(texture(r::TEX_NOISE), "HAS_NOISE_TEXTURE");
    add(texture(r::TEX_CHECKER), "HAS_CHECKER_TEXTURE");
    add(scene.sampler == r::SAMPLER_JITTERED, "HAS_JITTERED");
    add(scene.sampler == r::SAMPLER_HAMMERSLEY, "HAS_HAMMERSLEY");
    add(scene.sampler == r::SAMPLER_SOBOL, "HAS_SOBOL");
    // lights are sampled only toward surfaces with a lobe that is not a delta
    // (`nee_applies`: Lambertian or microfacet), and only when there are lights
    let lit = !scene.emitters.is_empty() && (mat(r::MAT_LAMBERTIAN) || mat(r::MAT_MICROFACET));
    add(
        lit && scene.light_sampling == r::LIGHT_SAMPLING_MIS,
        "HAS_MIS",
    );
    add(
        lit && scene.light_sampling == r::LIGHT_SAMPLING_MIXTURE,
        "HAS_MIXTURE",
    );
    add(scene.env.is_some(), "HAS_ENV_MAP");
    add(scene_emits(scene), "HAS_EMISSION");
    for name in uniform_defines(scene) {
        add(scene.uniform_records, name);
    }
    defines
}

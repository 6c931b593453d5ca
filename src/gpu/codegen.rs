//! WGSL written from Rust: the constants both languages read (from
//! `scene::records::SHARED_CONSTANTS` and the material tags), the materials' views of the
//! record and the dispatch to each material's functions (from the type list,
//! `scene::materials`), and, for a small scene, its records as constants with the searches
//! over them. Each is a file the preprocessor's `#import generated/...` pulls in
//! (`gpu::plan::ShaderSpec::wgsl`).

use crate::scene::flat::FlatScene;
use crate::scene::materials::common::{Field, FieldKind, Surface, View};
use crate::scene::materials::{self, MaterialKind};
use crate::scene::primitives::{self, PrimitiveKind};
use crate::scene::records::{FieldValue, SharedRecord, SharedValue, SHARED_CONSTANTS};

/// Every constant the shaders get from Rust: the shared constants, then the material and
/// primitive tags.
pub fn shared_constants() -> Vec<(String, SharedValue)> {
    SHARED_CONSTANTS
        .iter()
        .map(|&(name, value)| (name.to_string(), value))
        .chain(
            materials::tag_constants()
                .into_iter()
                .chain(primitives::tag_constants())
                .map(|(name, tag)| (name, SharedValue::U32(tag))),
        )
        .collect()
}

/// `const` declarations of every shared constant (`#import generated/constants`).
pub fn constants() -> String {
    shared_constants()
        .iter()
        .map(|(name, value)| match value {
            SharedValue::U32(v) => format!("const {name}: u32 = {v}u;\n"),
            SharedValue::F32(v) => format!("const {name}: f32 = {};\n", wgsl_f32(*v)),
        })
        .collect()
}

/// The materials of a shader (`#import generated/materials`, in shared/materials.wgsl):
/// the surface view every material has; for each type in `kinds`, its file
/// (`#import materials/NAME`) and its view; and the dispatch by the record's tag to the
/// functions a type has: `NAME_scatter` with any lobe, `NAME_eval` and `NAME_pdf` with a
/// lobe that has a density (`MaterialKind::lobes`), `NAME_textures` with textures of its
/// own (`View::own_textures`); the default case (absorb, 0, the material as it is) serves
/// the rest, and unknown tags. A case that only repeats the default costs llvmpipe code
/// for nothing (a switch of identities even changed how it folds constants, and with that
/// the last bits of an image), so there is none, nor a switch without cases.
pub fn materials(kinds: &[MaterialKind]) -> String {
    let mut code = String::from(
        "// Written by gpu::codegen::materials from the type list and the views of \
         scene::materials.\n#import shared/bsdf\n#import shared/types\n",
    );
    for k in kinds {
        code += &format!("#import materials/{}\n", k.name());
    }
    code += &view(&Surface::VIEW, "surface");
    for k in kinds {
        code += &view(k.view(), k.name());
    }
    let dispatch = |signature: &str, kinds: &[MaterialKind], call: &str, default: &str| {
        let cases: Vec<(&str, String)> = kinds.iter().map(|k| (k.name(), k.wgsl_tag())).collect();
        switch(signature, "mat.tag", &cases, call, default)
    };
    let having = |has: fn(&MaterialKind) -> bool| -> Vec<MaterialKind> {
        kinds.iter().copied().filter(has).collect()
    };
    code += "// Scattering by the material's type.\n";
    code += &dispatch(
        "fn scatter(mat: Material, ray: Ray, hit: Hit, u: vec2<f32>) -> Scatter",
        &having(|k| k.lobes().any()),
        "NAME_scatter(NAME_params(mat), ray, hit, u)",
        "absorbed()",
    );
    code += "// BSDF x cos for unit wo and wi about the unit normal n on wo's side.\n";
    code += &dispatch(
        "fn material_eval(mat: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32>",
        &having(|k| k.lobes().density),
        "NAME_eval(NAME_params(mat), n, wo, wi)",
        "vec3<f32>(0.0)",
    );
    code += "// The density of the material's sampling.\n";
    code += &dispatch(
        "fn material_pdf(mat: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32",
        &having(|k| k.lobes().density),
        "NAME_pdf(NAME_params(mat), n, wo, wi)",
        "0.0",
    );
    code += "// The look-ups of the material's own textures.\n";
    code += &dispatch(
        "fn material_textures(mat: Material, hit: Hit) -> Material",
        &having(|k| k.view().own_textures()),
        "NAME_record(NAME_textures(NAME_params(mat), hit), mat)",
        "mat",
    );
    code
}

/// A function of `signature` that switches on `on` over `cases` (name, tag constant):
/// each returns `call` with `NAME` replaced by its name; the default case `default`. No
/// switch without cases.
fn switch(
    signature: &str,
    on: &str,
    cases: &[(&str, String)],
    call: &str,
    default: &str,
) -> String {
    let mut f = format!("{signature} {{\n");
    if cases.is_empty() {
        return f + &format!("    return {default};\n}}\n");
    }
    f += &format!("    switch {on} {{\n");
    for (name, tag) in cases {
        let call = call.replace("NAME", name);
        f += &format!("        case {tag}: {{\n            return {call};\n        }}\n");
    }
    f + &format!("        default: {{\n            return {default};\n        }}\n    }}\n}}\n")
}

/// The primitives of a shader (`#import generated/primitives`, in shared/intersect.wgsl):
/// for each type in `kinds`, its file (`#import primitives/NAME`) and its view
/// (`NAME_params(m: Primitive)`); the dispatch by tag to its functions: `intersect_local`
/// (`NAME_intersect`), `surface_local` (`NAME_surface`), `surface_uv_derivatives`
/// (`NAME_uv_derivatives`, with HAS_BUMP); `intersect_each_type`, the plain loop as one
/// loop per bounded type in the type list's order (`scene::primitives::sort_for_loops`
/// sorts the records so), each ending at the first record of another type, visiting the
/// indices in order as the CPU's single loop does; and for the types that can be lights
/// (`PrimitiveKind::light`), `shape_light_sample`, `shape_light_pdf` and
/// `shape_light_distance` on an emitter's record, by its kind (its primitive's tag).
pub fn primitives(kinds: &[PrimitiveKind]) -> String {
    let mut code = String::from(
        "// Written by gpu::codegen::primitives from the type list and the views of \
         scene::primitives.\n#import shared/geometry\n#import shared/types\n",
    );
    for k in kinds {
        code += &format!("#import primitives/{}\n", k.name());
    }
    for k in kinds {
        code += &view(k.view(), k.name());
    }
    let cases = |light: bool| -> Vec<(&str, String)> {
        kinds
            .iter()
            .filter(|k| !light || k.light())
            .map(|k| (k.name(), k.wgsl_tag()))
            .collect()
    };
    code += "// One primitive of type `tag` in its own space: (t, u, v) as in Candidate.\n";
    code += &switch(
        "fn intersect_local(prim: Primitive, tag: u32, ray: Ray, t_max: f32) -> vec3<f32>",
        "tag",
        &cases(false),
        "NAME_intersect(NAME_params(prim), ray, t_max)",
        "vec3<f32>(FAR, 0.0, 0.0)",
    );
    code +=
        "// Hit point, normals, uv and error bound of a candidate in the primitive's own space.\n";
    code += &switch(
        "fn surface_local(prim: Primitive, ray: Ray, cand: Candidate) -> Surface",
        "prim.tag",
        &cases(false),
        "NAME_surface(NAME_params(prim), ray, cand)",
        "blank_surface()",
    );
    code += "#ifdef HAS_BUMP\n// The derivatives of the point along the first uv set, in the primitive's own space.\n";
    code += &switch(
        "fn surface_uv_derivatives(prim: Primitive, s: Surface, cand: Candidate) -> array<vec3<f32>, 2>",
        "prim.tag",
        &cases(false),
        "NAME_uv_derivatives(NAME_params(prim), s, cand)",
        "onb_tangents(s.ng)",
    );
    code += "#endif\n";
    code += "// The plain loop over the bounded primitives, one loop per type.\n\
             fn intersect_each_type(ray: Ray, start: Candidate) -> Candidate {\n    \
             var best = start;\n    var i = params.num_unbounded;\n";
    for k in kinds.iter().filter(|k| k.bounded()) {
        code += &format!(
            "    for (; i < params.num_primitives; i++) {{\n        \
             let prim = primitive_record(i);\n        \
             if (prim.tag != {tag}) {{\n            break;\n        }}\n        \
             best = closer_hit(best, i, intersect_record(prim, {tag}, ray, best.t));\n    }}\n",
            tag = k.wgsl_tag()
        );
    }
    code += "    return best;\n}\n";
    code += "// A point on light e seen from `origin`, by its primitive type.\n";
    code += &switch(
        "fn shape_light_sample(e: Emitter, origin: vec3<f32>, u: vec2<f32>) -> LightPoint",
        "e.kind",
        &cases(true),
        "NAME_light_sample(NAME_params(emitter_shape(e)), e.area, origin, u)",
        "LightPoint(vec3<f32>(0.0), 0.0, vec2<f32>(0.0))",
    );
    code += "// The solid-angle pdf of shape_light_sample toward x on light e.\n";
    code += &switch(
        "fn shape_light_pdf(e: Emitter, origin: vec3<f32>, x: vec3<f32>) -> f32",
        "e.kind",
        &cases(true),
        "NAME_light_pdf(NAME_params(emitter_shape(e)), e.area, origin, x)",
        "0.0",
    );
    code += "// Where the ray from `origin` along unit d meets light e as its sampling sees it.\n";
    code += &switch(
        "fn shape_light_distance(e: Emitter, origin: vec3<f32>, d: vec3<f32>) -> f32",
        "e.kind",
        &cases(true),
        "NAME_light_distance(NAME_params(emitter_shape(e)), origin, d)",
        "FAR",
    );
    code
}

/// A view in WGSL: its struct, `NAME_params(m: RECORD)` reading each field from its place
/// in its record (`Material` or `Primitive`), and for a material's, `NAME_record(p, m)`,
/// `m` with the fields written back. A view without fields gets one unused member (WGSL
/// has no empty structs).
fn view(v: &View, name: &str) -> String {
    let ty = v.wgsl_struct;
    let place = |f: &Field, of: &str| match (f.kind, f.lane) {
        (FieldKind::Rgb | FieldKind::Vec3, _) => format!("{of}.{}.xyz", f.place),
        (_, Some(lane)) => format!("{of}.{}.{lane}", f.place),
        (_, None) => format!("{of}.{}", f.place),
    };
    let mut code = format!("struct {ty} {{\n");
    for f in v.fields {
        code += &format!("    {}: {},\n", f.name, f.kind.wgsl());
    }
    let values = if v.fields.is_empty() {
        code += "    unused: u32,\n";
        "0u".to_string()
    } else {
        let values: Vec<String> = v.fields.iter().map(|f| place(f, "m")).collect();
        values.join(", ")
    };
    let record = v.record;
    code +=
        &format!("}}\nfn {name}_params(m: {record}) -> {ty} {{\n    return {ty}({values});\n}}\n");
    if record != "Material" {
        return code;
    }
    code += &format!("fn {name}_record(p: {ty}, m: Material) -> Material {{\n    var r = m;\n");
    for f in v.fields {
        code += &match f.kind {
            FieldKind::Rgb | FieldKind::Vec3 => {
                format!("    r.{0} = vec4<f32>(p.{1}, r.{0}.w);\n", f.place, f.name)
            }
            _ => format!("    {} = p.{};\n", place(f, "r"), f.name),
        };
    }
    code + "    return r;\n}\n"
}

/// A WGSL f32 literal that parses back to exactly `x` (naga reads a literal with the `f`
/// suffix as an f32; Rust's shortest round-trip form is exact).
pub fn wgsl_f32(x: f32) -> String {
    format!("{x:?}f")
}

fn wgsl_vec(v: &[f32]) -> String {
    let c: Vec<String> = v.iter().map(|&x| wgsl_f32(x)).collect();
    format!("vec{}<f32>({})", v.len(), c.join(", "))
}

/// `fn name(i: u32) -> R` reading record i of the texture `var` (`Placement::Texture`):
/// its texels, at `i * texels` from the start, `width` (a power of two) to a row, decoded
/// field by field from the layout [`SharedRecord`] gives (u32 components as they are,
/// floats by bitcast).
pub fn texture_accessor<R: SharedRecord + bytemuck::Zeroable>(
    name: &str,
    var: &str,
    width: u32,
) -> String {
    let layout = R::layout();
    let texels = layout.size.div_ceil(16);
    let shift = width.trailing_zeros();
    let mut code = format!(
        "fn {name}(i: u32) -> {} {{\n    let base = i * {texels}u;\n",
        R::NAME
    );
    for t in 0..texels {
        code += &format!(
            "    let t{t} = textureLoad({var}, vec2<u32>((base + {t}u) & {}u, (base + {t}u) >> {shift}u));\n",
            width - 1
        );
    }
    let zero: R = bytemuck::Zeroable::zeroed();
    let fields: Vec<String> = layout
        .fields
        .iter()
        .zip(zero.fields())
        .map(|(&(_, offset), (_, kind))| {
            let (t, c) = (offset / 16, offset % 16 / 4);
            let lanes = |n: usize| &"xyzw"[c..c + n];
            match kind {
                FieldValue::U32(_) => format!("t{t}.{}", lanes(1)),
                FieldValue::F32(_) => format!("bitcast<f32>(t{t}.{})", lanes(1)),
                FieldValue::Vec3(_) => format!("bitcast<vec3<f32>>(t{t}.{})", lanes(3)),
                FieldValue::Vec4(_) => format!("bitcast<vec4<f32>>(t{t})"),
                FieldValue::UVec4(_) => format!("t{t}"),
            }
        })
        .collect();
    code + &format!("    return {}({});\n}}\n", R::NAME, fields.join(", "))
}

/// A record as a WGSL constructor, its fields in the order [`SharedRecord`] lists them.
pub fn wgsl_record<R: SharedRecord>(r: &R) -> String {
    let values: Vec<String> = r
        .fields()
        .into_iter()
        .map(|(_, v)| match v {
            FieldValue::U32(x) => format!("{x}u"),
            FieldValue::F32(x) => wgsl_f32(x),
            FieldValue::Vec3(x) => wgsl_vec(&x),
            FieldValue::Vec4(x) => wgsl_vec(&x),
            FieldValue::UVec4(x) => {
                format!("vec4<u32>({}u, {}u, {}u, {}u)", x[0], x[1], x[2], x[3])
            }
        })
        .collect();
    format!("{}({})", R::NAME, values.join(", "))
}

/// The code for a scene whose primitives are written into its shader (`BAKED_PRIMITIVES`):
/// `intersect_baked`, the closest-hit search with every primitive's record a constant,
/// tested in index order as the CPU's loop does. llvmpipe loads a record from a uniform
/// buffer with a gather per component even at a constant index; a constant costs nothing
/// (1.9x on the Cornell box in alternating runs; docs/performance.md has all the records
/// written in as one row). Also `occluded_baked`, the any-hit search of shadow rays (no
/// closest hit to keep: 2% fewer instructions in the Cornell box's bounce loop), and
/// `primitive_record`, for `surface_at`. The plan decides when (`gpu::plan`).
pub fn baked_primitives(scene: &FlatScene) -> String {
    let prims = &scene.primitives;
    let mut code = format!(
        "// The scene's {} primitives as constants (gpu::codegen::baked_primitives).\n\
         fn intersect_baked(ray: Ray, t_max: f32) -> Candidate {{\n    \
         var best = Candidate(t_max, NO_HIT, 0.0, 0.0);\n",
        prims.len()
    );
    let records: Vec<String> = prims.iter().map(wgsl_record).collect();
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
    code + &record_lookup("primitive_record", "Primitive", &records)
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

/// `material_record` picking a record among constants (`BAKED_MATERIALS`) instead of
/// gathering it from a uniform buffer lane by lane: 1.35x on the Cornell box with the
/// emitters', and the primitive records 1.1x more.
pub fn baked_materials(scene: &FlatScene) -> String {
    let records: Vec<String> = scene.materials.iter().map(wgsl_record).collect();
    record_lookup("material_record", "Material", &records)
}

/// `emitter_record` among constants (`BAKED_EMITTERS`), and `choose_light_baked`:
/// choose_light's binary search as a count of the running sums at or below u, the same
/// index as the sums never decrease (1.7% fewer instructions in the Cornell box's bounce
/// loop).
pub fn baked_emitters(scene: &FlatScene) -> String {
    let records: Vec<String> = scene.emitters.iter().map(wgsl_record).collect();
    let mut code = record_lookup("emitter_record", "Emitter", &records);
    code += "fn choose_light_baked(u: f32) -> u32 {\n    var i = 0u;\n";
    // choose_light picks among the lights with a surface and the image background only
    let sampled = scene.emitters.len() - scene.num_punctual as usize;
    for e in &scene.emitters[..sampled.saturating_sub(1)] {
        code += &format!("    i += select(0u, 1u, u >= {});\n", wgsl_f32(e.cdf));
    }
    code + "    return i;\n}\n"
}

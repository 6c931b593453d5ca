//! Shader sources and the small preprocessor that assembles them.
//!
//! Directives (each alone on its line):
//! - `#import shared/name` pulls in `shaders/shared/name.wgsl`, once per assembled shader;
//!   `#import materials/NAME` a material's shading (`shaders/materials/NAME.wgsl`, which
//!   the generated dispatch imports), `#import primitives/NAME` a primitive's
//!   (`shaders/primitives/NAME.wgsl`, likewise); `#import generated/name` a file written from Rust
//!   (`gpu::codegen`, `gpu::bindings`);
//! - `#if NAME` / `#ifdef NAME`, `#ifndef NAME`, `#else`, `#endif` keep or drop lines by
//!   whether `NAME` is in the set of defines (they nest). A name that is no define at all
//!   (not among the names the caller knows) is an error: a misspelled `#ifdef` would
//!   otherwise leave its code out without a word.
//!
//! What to assemble for a scene is its plan's business (`gpu::plan::ShaderSpec::wgsl`).

use std::collections::BTreeSet;

/// The shader files of the entry points and the shared concerns, by the name `#import`
/// uses; embedded so the binary runs from anywhere.
const BASE_FILES: &[(&str, &str)] = &[
    ("trace", include_str!("../../shaders/trace.wgsl")),
    ("kernel", include_str!("../../shaders/kernel.wgsl")),
    (
        "shared/bindings",
        include_str!("../../shaders/shared/bindings.wgsl"),
    ),
    (
        "shared/bsdf",
        include_str!("../../shaders/shared/bsdf.wgsl"),
    ),
    (
        "shared/geometry",
        include_str!("../../shaders/shared/geometry.wgsl"),
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
    (
        "shared/media",
        include_str!("../../shaders/shared/media.wgsl"),
    ),
    (
        "shared/path",
        include_str!("../../shaders/shared/path.wgsl"),
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

macro_rules! material_files {
    ($( $(#[$doc:meta])* $kind:ident = $tag:literal, $module:ident, $define:literal; )*) => {
        /// Each material's shading (`materials/NAME`), from the type list.
        const MATERIAL_FILES: &[(&str, &str)] = &[
            $( (
                concat!("materials/", stringify!($module)),
                include_str!(concat!("../../shaders/materials/", stringify!($module), ".wgsl")),
            ), )*
        ];
    };
}

crate::scene::materials::for_each_material!(material_files);

macro_rules! primitive_files {
    ($( $(#[$doc:meta])* $kind:ident = $tag:literal, $module:ident, $name:literal, $define:literal; )*) => {
        /// Each primitive's functions (`primitives/NAME`), from the type list.
        const PRIMITIVE_FILES: &[(&str, &str)] = &[
            $( (
                concat!("primitives/", $name),
                include_str!(concat!("../../shaders/primitives/", $name, ".wgsl")),
            ), )*
        ];
    };
}

crate::scene::primitives::for_each_primitive!(primitive_files);

/// Every shader file, by the name `#import` uses: the entry points and shared files, each
/// material's and each primitive's.
pub fn shader_files() -> Vec<(&'static str, &'static str)> {
    [BASE_FILES, MATERIAL_FILES, PRIMITIVE_FILES].concat()
}

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

/// The names a shader's `#if` may ask about, and which of them are defined.
#[derive(Debug, Clone, Copy)]
pub struct Defines<'a> {
    /// Every name a directive may name (`gpu::plan::ShaderSpec::known_defines`).
    pub known: &'a BTreeSet<&'a str>,
    /// The ones defined for this shader.
    pub set: &'a BTreeSet<&'a str>,
}

/// Assembles shader `entry` with its imports from [`shader_files`] and the `generated`
/// files, keeping the `#if` branches `defines` selects.
pub fn assemble(
    entry: &str,
    defines: Defines,
    generated: &[(&str, &str)],
) -> Result<String, ShaderError> {
    let mut files = shader_files();
    files.extend_from_slice(generated);
    preprocess_files(entry, defines, &files)
}

/// The preprocessor over a given set of `(name, source)` files.
pub fn preprocess_files(
    entry: &str,
    defines: Defines,
    files: &[(&str, &str)],
) -> Result<String, ShaderError> {
    if let Some(unknown) = defines.set.difference(defines.known).next() {
        return Err(ShaderError::Preprocess {
            file: entry.to_string(),
            line: 0,
            message: format!("{unknown} is defined but not a known name"),
        });
    }
    let mut out = String::new();
    let mut imported = BTreeSet::new();
    imported.insert(entry.to_string());
    expand(entry, defines, files, &mut imported, &mut out)?;
    Ok(out)
}

fn expand(
    name: &str,
    defines: Defines,
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
                if !defines.known.contains(flag) {
                    return Err(err(
                        lineno,
                        format!("{d} {flag}: no such define{}", closest(flag, defines.known)),
                    ));
                }
                let outer = active(&stack);
                let on = defines.set.contains(flag) != (d == "#ifndef");
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

/// `; did you mean NAME?` for the known name closest to `flag`, when one is close.
fn closest(flag: &str, known: &BTreeSet<&str>) -> String {
    known
        .iter()
        .map(|k| (strsim::levenshtein(flag, k), k))
        .min()
        .filter(|(d, _)| *d <= 3)
        .map_or(String::new(), |(_, k)| format!("; did you mean {k}?"))
}

/// Parses and validates assembled WGSL with naga, as wgpu will (the pipelines leave this to
/// wgpu; `wgtrace validate` and the tests call it).
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
    // subgroup operations only in `--tune lane-stats`'s shader (gpu::plan::LANE_STATS)
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default() | naga::valid::Capabilities::SUBGROUP,
    )
    .subgroup_stages(naga::valid::ShaderStages::COMPUTE)
    .subgroup_operations(
        naga::valid::SubgroupOperationSet::BASIC | naga::valid::SubgroupOperationSet::ARITHMETIC,
    )
    .validate(&module)
    .map_err(|e| invalid(e.emit_to_string(wgsl)))?;
    Ok((module, info))
}

/// The bindings of `group` that entry point `entry` of the assembled shader uses (reads,
/// writes or queries), in increasing order, by naga's analysis: the tests hold a plan's
/// `trace_slots` to it. A resource declared but reached only from code the defines left
/// out is not among them.
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

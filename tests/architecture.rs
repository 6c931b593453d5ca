//! The shape of the code: no source file in src/ imports, directly or through others, a
//! file that imports it back; and every test in the repository is in a target that
//! `cargo test` builds and runs. No GPU needed.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `src` with comments, string and character literals blanked (newlines kept), so that
/// paths named in docs or messages are not taken for imports.
/// Whether `rest` starts a raw string (`r"..."`, `r#"..."#`), not a raw identifier
/// (`r#box`).
fn raw_string(rest: &[u8]) -> bool {
    let hashes = rest.iter().skip(1).take_while(|&&c| c == b'#').count();
    rest.first() == Some(&b'r') && rest.get(1 + hashes) == Some(&b'"')
}

fn code_only(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    let blank = |out: &mut String, s: &[u8]| {
        for &c in s {
            out.push(if c == b'\n' { '\n' } else { ' ' });
        }
    };
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    while i < b.len() {
        let rest = &b[i..];
        let prev_ident = i > 0 && ident(b[i - 1]);
        let end = if rest.starts_with(b"//") {
            i + rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len())
        } else if rest.starts_with(b"/*") {
            // block comments nest in Rust
            let (mut depth, mut j) = (0, i);
            while j < b.len() {
                if b[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if b[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            j
        } else if !prev_ident && raw_string(rest) {
            let hashes = rest[1..].iter().take_while(|&&c| c == b'#').count();
            let close: Vec<u8> = std::iter::once(b'"')
                .chain(std::iter::repeat_n(b'#', hashes))
                .collect();
            let body = i + 2 + hashes;
            body + b[body..]
                .windows(close.len())
                .position(|w| w == close.as_slice())
                .map_or(b.len() - body, |p| p + close.len())
        } else if rest[0] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            (j + 1).min(b.len())
        } else if rest[0] == b'\'' {
            // a character literal ('a', '\n', '\u{..}'), not a lifetime ('a)
            let lit = if rest.get(1) == Some(&b'\\') {
                rest[2..].iter().position(|&c| c == b'\'').map(|p| p + 3)
            } else if rest.len() > 2 && rest[2] == b'\'' {
                Some(3)
            } else {
                None
            };
            match lit {
                Some(n) => i + n,
                None => {
                    out.push('\'');
                    i += 1;
                    continue;
                }
            }
        } else {
            out.push(rest[0] as char);
            i += 1;
            continue;
        };
        blank(&mut out, &b[i..end]);
        i = end;
    }
    out
}

/// Every Rust file of `src/`, by its module path (`scene::flatten`; the crate root is "").
fn modules() -> BTreeMap<String, PathBuf> {
    fn walk(dir: &Path, prefix: &[String], out: &mut BTreeMap<String, PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                let mut sub = prefix.to_vec();
                sub.push(stem);
                walk(&p, &sub, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let mut path = prefix.to_vec();
                if stem != "mod" && stem != "lib" {
                    path.push(stem);
                }
                out.insert(path.join("::"), p);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(&root().join("src"), &[], &mut out);
    out
}

/// The paths a file's code names: every `use` tree expanded (`use a::{b, c::d}` gives
/// `a::b` and `a::c::d`), every `mod` it declares, and every path written in the code
/// that starts at `crate`, `super`, `self` or (in main.rs) `wgtrace`.
fn named_paths(code: &str) -> Vec<(Vec<String>, bool)> {
    fn expand(tree: &str, prefix: &[String], out: &mut Vec<Vec<String>>) {
        let tree = tree.trim();
        if let Some(open) = tree.find('{') {
            let head: Vec<String> = tree[..open]
                .split("::")
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect();
            let inner = &tree[open + 1..tree.rfind('}').unwrap()];
            let mut depth = 0;
            let mut start = 0;
            let mut parts = Vec::new();
            for (k, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        parts.push(&inner[start..k]);
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            parts.push(&inner[start..]);
            let full: Vec<String> = prefix.iter().cloned().chain(head).collect();
            for part in parts.into_iter().filter(|p| !p.trim().is_empty()) {
                expand(part, &full, out);
            }
        } else {
            let path = tree.split(" as ").next().unwrap();
            let mut full = prefix.to_vec();
            full.extend(
                path.split("::")
                    .map(str::trim)
                    .filter(|s| !s.is_empty() && (*s != "self" || prefix.is_empty()))
                    .map(String::from),
            );
            out.push(full);
        }
    }
    let mut out = Vec::new();
    let words: Vec<&str> = code.split_whitespace().collect();
    // `use` statements (also `pub use`, `pub(crate) use`)
    let mut rest = code;
    while let Some(k) = rest.find("use ") {
        let before = rest[..k].chars().last();
        let after = &rest[k + 4..];
        if before.is_none_or(|c| !(c.is_alphanumeric() || c == '_')) {
            let end = after.find(';').unwrap_or(after.len());
            let mut trees = Vec::new();
            expand(&after[..end], &[], &mut trees);
            out.extend(trees.into_iter().map(|t| (t, true)));
            rest = &after[end..];
        } else {
            rest = after;
        }
    }
    // `mod name;` declarations
    for w in words.windows(2) {
        if w[0] == "mod" && w[1].ends_with(';') {
            out.push((vec!["self".into(), w[1].trim_end_matches(';').into()], true));
        }
    }
    // paths in expressions and types
    let bytes = code.as_bytes();
    for start in ["crate::", "super::", "wgtrace::"] {
        let mut from = 0;
        while let Some(k) = code[from..].find(start) {
            let at = from + k;
            from = at + start.len();
            if at > 0
                && (bytes[at - 1].is_ascii_alphanumeric()
                    || bytes[at - 1] == b'_'
                    || bytes[at - 1] == b':')
            {
                continue;
            }
            let end = code[at..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .map_or(code.len(), |e| at + e);
            // the head of a `use` group (`use super::{a, b}`): its paths are the group's
            if code[end..].starts_with('{') {
                continue;
            }
            let segs: Vec<String> = code[at..end]
                .split("::")
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect();
            out.push((segs, false));
        }
    }
    out
}

/// Resolves a path named in the file of module `here` to the file of the deepest module
/// along it, or None for another crate (std, glam, ...).
fn resolve(
    here: &str,
    here_is_dir: bool,
    path: &[String],
    children: &BTreeSet<String>,
    mods: &BTreeMap<String, PathBuf>,
    bin: bool,
) -> Option<String> {
    let here_segs: Vec<String> = here
        .split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    // the module a `self` path is relative to: a mod.rs or lib.rs is its own module; for
    // `super` in a leaf file (scene/flatten.rs), the parent is `scene`
    let mut base: Vec<String>;
    let mut segs = path.iter().peekable();
    match segs.peek().map(|s| s.as_str()) {
        Some("crate") if !bin => {
            base = Vec::new();
            segs.next();
        }
        Some("wgtrace") if bin => {
            base = Vec::new();
            segs.next();
        }
        Some("self") => {
            base = here_segs.clone();
            segs.next();
        }
        Some("super") => {
            base = here_segs.clone();
            while segs.peek().map(|s| s.as_str()) == Some("super") {
                segs.next();
                base.pop();
            }
            let _ = here_is_dir;
        }
        Some(first) if children.contains(first) => base = here_segs.clone(),
        _ => return None,
    }
    // the deepest module along the path; a path that names an item (`super::FlatScene`)
    // or nothing more (`super::{..}`) names the module it has reached
    let mut found = base.join("::");
    for s in segs {
        base.push(s.clone());
        let key = base.join("::");
        if !mods.contains_key(&key) {
            break;
        }
        found = key;
    }
    mods.contains_key(&found).then_some(found)
}

#[test]
fn no_source_file_imports_a_file_that_imports_it_back() {
    let mods = modules();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, file) in &mods {
        let code = code_only(&std::fs::read_to_string(file).unwrap());
        let is_dir = file
            .file_name()
            .is_some_and(|n| n == "mod.rs" || n == "lib.rs");
        let bin = file.ends_with("src/main.rs");
        let children: BTreeSet<String> = code
            .split_whitespace()
            .collect::<Vec<_>>()
            .windows(2)
            .filter(|w| w[0] == "mod")
            .map(|w| w[1].trim_end_matches(';').to_string())
            .collect();
        let node = if bin {
            "main".to_string()
        } else {
            module.clone()
        };
        let edges = graph.entry(node.clone()).or_default();
        for (path, _) in named_paths(&code) {
            if let Some(target) = resolve(module, is_dir, &path, &children, &mods, bin) {
                if target != node {
                    edges.insert(target);
                }
            }
        }
    }
    // every file imports something (a parser that found nothing would pass vacuously)
    assert!(
        graph["scene::flatten"].contains("scene::records"),
        "{graph:?}"
    );
    assert!(graph[""].contains("scene"), "{:?}", graph[""]);
    // a cycle is a path from a file back to itself
    let mut cycles = Vec::new();
    for start in graph.keys() {
        let mut stack = vec![(start.clone(), vec![start.clone()])];
        let mut seen = BTreeSet::new();
        while let Some((node, trail)) = stack.pop() {
            for next in graph.get(&node).into_iter().flatten() {
                if next == start {
                    let mut cycle = trail.clone();
                    cycle.push(start.clone());
                    cycles.push(cycle);
                } else if seen.insert(next.clone()) {
                    let mut t = trail.clone();
                    t.push(next.clone());
                    stack.push((next.clone(), t));
                }
            }
        }
    }
    let shown: BTreeSet<String> = cycles
        .iter()
        .map(|c| {
            c.iter()
                .map(|m| if m.is_empty() { "lib" } else { m.as_str() })
                .collect::<Vec<_>>()
                .join(" -> ")
        })
        .collect();
    assert!(
        shown.is_empty(),
        "import circles in src/ (module -> module it imports):\n{}",
        shown.into_iter().collect::<Vec<_>>().join("\n")
    );
}

/// Every `#[test]` of the repository is in a target `cargo test` builds and runs: tests/
/// (always), src/main.rs (the binary's tests are on), an example whose `[[example]]` entry
/// sets `test = true`; the library's own harness is off, so src/ holds no other tests.
#[test]
fn every_test_in_the_repository_runs_under_cargo_test() {
    let manifest: toml::Table =
        toml::from_str(&std::fs::read_to_string(root().join("Cargo.toml")).unwrap()).unwrap();
    let targets = |kind: &str| -> Vec<toml::Table> {
        manifest
            .get(kind)
            .and_then(|v| v.as_array())
            .map(|a| a.iter().filter_map(|t| t.as_table().cloned()).collect())
            .unwrap_or_default()
    };
    let tested = |t: &toml::Table| t.get("test").and_then(|v| v.as_bool());
    let lib_tests = manifest
        .get("lib")
        .and_then(|l| l.as_table())
        .and_then(tested)
        .unwrap_or(true);
    let bin_tests = targets("bin")
        .iter()
        .find(|b| b.get("name").and_then(|n| n.as_str()) == Some("wgtrace"))
        .and_then(tested)
        .unwrap_or(true);
    let has_tests = |p: &Path| {
        let code = code_only(&std::fs::read_to_string(p).unwrap());
        code.contains("#[test]") || code.contains("#[cfg(test)]")
    };
    let mut missed = Vec::new();
    for file in modules().values() {
        let runs = if file.ends_with("src/main.rs") {
            bin_tests
        } else {
            lib_tests
        };
        if !runs && has_tests(file) {
            missed.push(file.display().to_string());
        }
    }
    for (dir, kind) in [("examples", "example"), ("benches", "bench")] {
        for e in std::fs::read_dir(root().join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "rs") || !has_tests(&p) {
                continue;
            }
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            let on = targets(kind)
                .iter()
                .find(|t| t.get("name").and_then(|n| n.as_str()) == Some(name.as_str()))
                .and_then(tested)
                // examples' tests are off by default; benches never run under cargo test
                .unwrap_or(false);
            if !on || kind == "bench" {
                missed.push(p.display().to_string());
            }
        }
    }
    assert!(
        missed.is_empty(),
        "tests that `cargo test` never runs: {missed:?}"
    );
}

/// The material record's places have meanings only in the material layer: outside the
/// views (`src/scene/materials/`, written into WGSL by `gpu::codegen`), the record's own
/// file and its rules (`material_at` and the alpha of `transparent_at`, in
/// `shaders/shared/materials.wgsl` and its twin `src/cpu/materials/mod.rs`), no code of
/// the repository, tests included, reads or writes the places that mean one thing for one
/// material and another for the next. A record built by hand, or a `scalars.x` read as a
/// roughness, fails here: use the material's `Params` or `common::material`.
#[test]
fn material_places_are_named_only_by_the_material_layer() {
    const PLACES: [&str; 16] = [
        "scalars",
        "scalars2",
        "color2",
        "color3",
        "normal2",
        "tex_data2",
        "tex_data3",
        "tex_data4",
        "tex_data5",
        "tex_normal2",
        "tex_color",
        "tex_color2",
        "tex_data0",
        "tex_data1",
        "tex_normal",
        "tex_emission",
    ];
    const LAYER: [&str; 6] = [
        "src/scene/records.rs",
        "src/scene/materials/",
        "src/cpu/materials/mod.rs",
        "shaders/shared/materials.wgsl",
        "shaders/shared/types.wgsl",
        "tests/architecture.rs",
    ];
    let mut files = Vec::new();
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs" || x == "wgsl") {
                out.push(p);
            }
        }
    }
    for dir in ["src", "shaders", "tests", "benches", "examples"] {
        walk(&root().join(dir), &mut files);
    }
    let mut found = Vec::new();
    let mut scanned = 0;
    for file in &files {
        let rel = file
            .strip_prefix(root())
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if LAYER.iter().any(|l| rel.starts_with(l)) {
            continue;
        }
        scanned += 1;
        let code = code_only(&std::fs::read_to_string(file).unwrap());
        for (i, line) in code.lines().enumerate() {
            // a field read or written (`m.scalars`), or set in a struct literal
            // (`scalars: [...]`, not a `let scalars: ...` of its own)
            let named = PLACES.iter().find(|place| {
                line.match_indices(*place).any(|(at, _)| {
                    let before = line[..at].trim_end();
                    let after = line[at + place.len()..].trim_start();
                    let whole = !line[..at]
                        .ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_')
                        && !after.starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_');
                    let field = before.ends_with('.')
                        || (after.starts_with(':')
                            && !after.starts_with("::")
                            && !before.ends_with("let")
                            && !before.ends_with("mut"));
                    whole && field
                })
            });
            if let Some(place) = named {
                found.push(format!("{rel}:{}: {place}: {}", i + 1, line.trim()));
            }
        }
    }
    assert!(scanned > 50, "scanned {scanned} files");
    assert!(
        found.is_empty(),
        "material places named outside the material layer:\n{}",
        found.join("\n")
    );
}

/// Holds the shading file `shaders/LAYER/NAME.wgsl` and its twin `src/cpu/LAYER/NAME.rs` to
/// one shape: every WGSL function is named `NAME_x` and has a twin `fn x`, and each
/// dispatched `NAME_f` of `dispatched` is defined exactly when it `has` to be (`why` says
/// what decides).
fn check_twins(layer: &str, name: &str, dispatched: &[(&str, bool)], why: &str) {
    let fns = |src: &str| -> Vec<String> {
        code_only(src)
            .split("fn ")
            .skip(1)
            .filter_map(|rest| {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                (!name.is_empty()).then_some(name)
            })
            .collect()
    };
    let wgsl = std::fs::read_to_string(root().join(format!("shaders/{layer}/{name}.wgsl")))
        .unwrap_or_else(|e| panic!("shaders/{layer}/{name}.wgsl: {e}"));
    let cpu = std::fs::read_to_string(root().join(format!("src/cpu/{layer}/{name}.rs")))
        .unwrap_or_else(|e| panic!("src/cpu/{layer}/{name}.rs: {e}"));
    let (gpu_fns, cpu_fns) = (fns(&wgsl), fns(&cpu));
    for f in &gpu_fns {
        let own = f
            .strip_prefix(&format!("{name}_"))
            .unwrap_or_else(|| panic!("{name}.wgsl: fn {f} is not named {name}_..."));
        assert!(
            cpu_fns.iter().any(|c| c == own),
            "{name}: fn {f} has no twin fn {own} in src/cpu/{layer}/{name}.rs"
        );
    }
    for &(f, has) in dispatched {
        let defined = gpu_fns.contains(&format!("{name}_{f}"));
        assert_eq!(
            defined,
            has,
            "{name}.wgsl: fn {name}_{f} {} by {why}",
            if has { "is needed" } else { "is never called" }
        );
    }
}

/// Each material's shading has one shape in both languages: `shaders/materials/NAME.wgsl`
/// defines only functions named `NAME_...`, and exactly the dispatched ones its type has
/// (`NAME_scatter` with a lobe, `NAME_eval` and `NAME_pdf` with a density,
/// `NAME_textures` with textures of its own); its twin `src/cpu/materials/NAME.rs`
/// implements those (`fn scatter`, ...) and every helper of the same name
/// (`NAME_spec_prob` is `fn spec_prob`).
#[test]
fn every_material_has_its_wgsl_and_its_cpu_twin_in_the_same_shape() {
    use wgtrace::scene::materials::MaterialKind;
    for &kind in MaterialKind::ALL {
        let lobes = kind.lobes();
        let dispatched = [
            ("scatter", lobes.any()),
            ("eval", lobes.density),
            ("pdf", lobes.density),
            ("textures", kind.view().own_textures()),
        ];
        check_twins(
            "materials",
            kind.name(),
            &dispatched,
            "its type's lobes and view",
        );
    }
}

/// Each primitive has one shape in both languages: `shaders/primitives/NAME.wgsl` defines
/// only functions named `NAME_...`, among them `NAME_intersect`, `NAME_surface` and
/// `NAME_uv_derivatives`, and the light functions (`NAME_light_sample`, `NAME_light_pdf`,
/// `NAME_light_distance`) exactly when its type can be a light; its twin
/// `src/cpu/primitives/NAME.rs` implements each of them under its own name (`fn
/// intersect`, ..., `NAME_cone` is `fn cone`). Its record view is its module's
/// (`scene::primitives::NAME::Params`): no file outside the layer names a shape's place.
#[test]
fn every_primitive_has_its_wgsl_and_its_cpu_twin_in_the_same_shape() {
    use wgtrace::scene::primitives::PrimitiveKind;
    assert!(PrimitiveKind::ALL.len() >= 6);
    for &kind in PrimitiveKind::ALL {
        let dispatched = [
            ("intersect", true),
            ("surface", true),
            ("uv_derivatives", true),
            ("light_sample", kind.light()),
            ("light_pdf", kind.light()),
            ("light_distance", kind.light()),
        ];
        check_twins(
            "primitives",
            kind.name(),
            &dispatched,
            "its type (PrimitiveKind::light)",
        );
    }
}

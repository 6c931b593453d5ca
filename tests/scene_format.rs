//! docs/scene-format.md against the scene format's serde model (src/scene/format.rs): every
//! table of the reference lists exactly the keys the parser accepts there, every
//! enumerated value is documented, every example parses, and the reference's minimal scene
//! loads. The parser's own error messages give the accepted keys and values: an unknown
//! key or `type` is rejected with the full list of what was expected. A key added to the
//! format without a row in the reference fails here.

use std::collections::{BTreeMap, BTreeSet};

use wgtrace::scene::format::SceneFile;

const DOC: &str = "docs/scene-format.md";
const PROBE: &str = "zz_probe";
const CAMERA: &str = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n";

/// One row of a reference table: the example `key = value` line and the range cell.
struct Row {
    example: String,
    range: String,
}

/// The reference's tables by section id (`render`, `textures.checker`, `objects.sphere`,
/// `transform`, `top`), each row by key.
fn reference() -> BTreeMap<String, BTreeMap<String, Row>> {
    let text = std::fs::read_to_string(DOC).expect("docs/scene-format.md");
    let mut sections: BTreeMap<String, BTreeMap<String, Row>> = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("### ") {
            let id = section_id(heading);
            assert!(
                !sections.contains_key(&id),
                "{DOC}: section {id} appears twice"
            );
            sections.insert(id.clone(), BTreeMap::new());
            current = Some(id);
        } else if line.starts_with("## ") {
            current = None;
        } else if let (Some(id), Some(row)) = (&current, line.strip_prefix("| `")) {
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            assert_eq!(
                cells.len(),
                7,
                "{DOC}: a row of {id} has not 6 cells: {line}"
            );
            let key = cells[0].trim_end_matches('`').to_string();
            let row = Row {
                example: cells[4].trim_matches('`').to_string(),
                range: cells[3].to_string(),
            };
            let old = sections.get_mut(id).unwrap().insert(key.clone(), row);
            assert!(old.is_none(), "{DOC}: {id} lists `{key}` twice");
        }
    }
    sections
}

/// `Top-level tables` -> top; `` `[render]` `` -> render; `` `[textures.NAME]` with
/// `type = "image"` `` -> textures.image; `` `transform` `` -> transform.
fn section_id(heading: &str) -> String {
    let ticks: Vec<&str> = heading.split('`').skip(1).step_by(2).collect();
    let Some(first) = ticks.first() else {
        return "top".to_string();
    };
    let table = first
        .trim_matches(|c| c == '[' || c == ']')
        .trim_end_matches(".NAME");
    match ticks.get(1).and_then(|t| t.strip_prefix("type = ")) {
        Some(kind) => format!("{table}.{}", kind.trim_matches('"')),
        None => table.to_string(),
    }
}

/// The names the parser's error lists after "expected" on the line that rejects
/// `zz_probe`.
fn expected(scene: &str) -> BTreeSet<String> {
    let err = toml::from_str::<SceneFile>(scene)
        .map(|_| ())
        .expect_err(scene)
        .to_string();
    // a table without keys (the `null` material's)
    if err.contains(&format!("unknown field `{PROBE}`, there are no fields")) {
        return BTreeSet::new();
    }
    let line = err
        .lines()
        .find(|l| l.contains(&format!("`{PROBE}`")) && l.contains("expected"))
        .unwrap_or_else(|| panic!("no list of expected names in: {err}"));
    let list = &line[line.find("expected").unwrap()..];
    list.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// A scene holding `lines` in the table of section `id`.
fn in_section(id: &str, lines: &str) -> String {
    let (table, kind) = id.split_once('.').unwrap_or((id, ""));
    match table {
        "top" => format!("{lines}\n{CAMERA}"),
        "camera" => format!("[camera]\n{lines}\n"),
        "render" | "background" => format!("{CAMERA}[{table}]\n{lines}\n"),
        "textures" => format!("{CAMERA}[textures.t]\ntype = \"{kind}\"\n{lines}\n"),
        "materials" => format!("{CAMERA}[materials.m]\ntype = \"{kind}\"\n{lines}\n"),
        "objects" => format!("{CAMERA}[[objects]]\ntype = \"{kind}\"\n{lines}\n"),
        "lights" => format!("{CAMERA}[[lights]]\ntype = \"{kind}\"\n{lines}\n"),
        "groups" => format!("{CAMERA}[groups.g]\n{lines}\n"),
        "media" => format!("{CAMERA}[media.f]\ntype = \"{kind}\"\n{lines}\n"),
        "transform" => format!(
            "{CAMERA}[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
             material = \"m\"\n[objects.transform]\n{lines}\n"
        ),
        _ => panic!("{DOC}: unexpected section {id}"),
    }
}

/// The parser's keys for every section the format has, and its `type`s per table.
fn code_sections() -> BTreeMap<String, BTreeSet<String>> {
    let mut out = BTreeMap::new();
    for id in [
        "top",
        "render",
        "camera",
        "background",
        "transform",
        "groups",
    ] {
        out.insert(
            id.to_string(),
            expected(&in_section(id, &format!("{PROBE} = 1"))),
        );
    }
    for table in ["textures", "materials", "objects", "lights", "media"] {
        let kinds = expected(&in_section(&format!("{table}.{PROBE}"), ""));
        assert!(
            kinds.len() >= 3 || table == "media",
            "{table}: only {kinds:?}"
        );
        for kind in kinds {
            let id = format!("{table}.{kind}");
            let keys = expected(&in_section(&id, &format!("{PROBE} = 1")));
            out.insert(id, keys);
        }
    }
    out
}

#[test]
fn every_key_of_the_format_is_documented_and_every_documented_key_exists() {
    let doc = reference();
    let code = code_sections();
    let doc_ids: BTreeSet<&String> = doc.keys().collect();
    let code_ids: BTreeSet<&String> = code.keys().collect();
    assert_eq!(
        doc_ids, code_ids,
        "{DOC}: the sections differ from the format's tables and types"
    );
    for (id, keys) in &code {
        let documented: BTreeSet<String> = doc[id].keys().cloned().collect();
        let missing: Vec<_> = keys.difference(&documented).collect();
        let extra: Vec<_> = documented.difference(keys).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "{DOC}, section {id}: undocumented keys {missing:?}, documented keys the parser \
             rejects {extra:?}"
        );
    }
}

#[test]
fn every_enumerated_value_is_documented() {
    let doc = reference();
    for (id, key) in [
        ("render", "sampler"),
        ("render", "light_sampling"),
        ("render", "reconstruction"),
        ("textures.checker", "mapping"),
        ("textures.image", "wrap"),
        ("textures.noise", "kind"),
    ] {
        let values = expected(&in_section(id, &format!("{key} = \"{PROBE}\"")));
        assert!(values.len() >= 2, "{id}.{key}: {values:?}");
        let range = &doc[id][key].range;
        for v in values {
            assert!(
                range.contains(&format!("`{v}`")),
                "{DOC}, {id}: the range of `{key}` does not list `{v}`: {range}"
            );
        }
    }
}

#[test]
fn every_example_parses_in_its_table() {
    let doc = reference();
    for (id, rows) in doc.iter().filter(|(id, _)| id.as_str() != "top") {
        for (key, row) in rows {
            assert!(
                row.example.starts_with(&format!("{key} =")),
                "{DOC}, {id}: the example of `{key}` does not set it: {}",
                row.example
            );
            // the example alone, then each missing field from its own row's example
            let mut lines = vec![row.example.clone()];
            loop {
                let scene = in_section(id, &lines.join("\n"));
                let err = match toml::from_str::<SceneFile>(&scene) {
                    Ok(_) => break,
                    Err(e) => e.to_string(),
                };
                let missing = err
                    .split("missing field `")
                    .nth(1)
                    .and_then(|rest| rest.split('`').next())
                    .filter(|field| rows.contains_key(*field) && lines.len() <= rows.len());
                match missing {
                    Some(field) => lines.push(rows[field].example.clone()),
                    None => panic!("{DOC}, {id}: the example of `{key}` fails: {err}\n{scene}"),
                }
            }
        }
    }
}

#[test]
fn the_reference_minimal_scene_loads() {
    let text = std::fs::read_to_string(DOC).unwrap();
    let start = text.find("```toml\n").expect("a toml block") + "```toml\n".len();
    let end = start + text[start..].find("```").unwrap();
    let scene = wgtrace::load_scene_str(
        &text[start..end],
        std::path::Path::new("scenes/minimal.toml"),
        &Default::default(),
    );
    assert!(
        scene.is_ok(),
        "{DOC}: the minimal scene fails: {:?}",
        scene.err()
    );
}

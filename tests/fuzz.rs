//! The scene loader on arbitrary and mutated input (proptest): it returns a scene or an
//! error naming the file, and never panics. Mutations start from every scene in `scenes/`
//! (so files they name still resolve) and insert tokens that break types, ranges and
//! syntax: NaN, infinities, huge and negative numbers, stray brackets and quotes, repeated
//! and swapped lines, cut ranges. No GPU needed.

mod common;

use proptest::prelude::*;
use proptest::sample::Index;
use wgtrace::Overrides;

/// Values a mutation puts in place of a number.
const VALUES: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0.0",
    "1e39",
    "1e-45",
    "0.5",
    "4294967296",
    "99999999999999999999",
    "16384",
    "16777217",
    "true",
    "\"nope\"",
    "[1, 2]",
    "[0, 0, 0]",
    "[nan, 0, 0]",
];

/// Syntax a mutation inserts anywhere (besides the values above).
const SYNTAX: &[&str] = &[
    "\"",
    "[",
    "]",
    "{",
    "}",
    "=",
    "\n",
    "[[objects]]\n",
    "[materials.x]\n",
    "\"lambertian\"",
];

/// One edit of a scene's text, positions given as indices into whatever length it has.
#[derive(Debug, Clone)]
enum Edit {
    Delete(Index, u8),
    Insert(Index, Index),
    ReplaceNumber(Index, Index),
    DuplicateLine(Index),
    SwapLines(Index, Index),
    Truncate(Index),
}

/// Mostly values replaced (reaching validation), sometimes syntax broken.
fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        1 => (any::<Index>(), any::<u8>()).prop_map(|(i, n)| Edit::Delete(i, n)),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(i, t)| Edit::Insert(i, t)),
        8 => (any::<Index>(), any::<Index>()).prop_map(|(i, t)| Edit::ReplaceNumber(i, t)),
        2 => any::<Index>().prop_map(Edit::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
        1 => any::<Index>().prop_map(Edit::Truncate),
    ]
}

/// The nearest char boundary at or before byte `i`.
fn boundary(s: &str, mut i: usize) -> usize {
    i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &mut String, e: &Edit) {
    let token = |t: &Index| {
        let k = t.index(VALUES.len() + SYNTAX.len());
        VALUES.get(k).unwrap_or_else(|| &SYNTAX[k - VALUES.len()])
    };
    let value = |t: &Index| VALUES[t.index(VALUES.len())];
    let at = |i: &Index, s: &str| boundary(s, i.index(s.len() + 1));
    match e {
        Edit::Delete(i, n) => {
            let a = at(i, text);
            let b = boundary(text, a + *n as usize % 16 + 1);
            text.replace_range(a..b, "");
        }
        Edit::Insert(i, t) => {
            let a = at(i, text);
            text.insert_str(a, token(t));
        }
        Edit::ReplaceNumber(i, t) => {
            // the first number at or after the position
            let a = at(i, text);
            let Some(start) = text[a..].find(|c: char| c.is_ascii_digit()).map(|k| a + k) else {
                return;
            };
            let end = text[start..]
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e'))
                .map_or(text.len(), |k| start + k);
            text.replace_range(start..end, value(t));
        }
        Edit::DuplicateLine(i) => {
            let mut lines: Vec<String> = text.lines().map(String::from).collect();
            if !lines.is_empty() {
                let k = i.index(lines.len());
                lines.insert(k, lines[k].clone());
                *text = lines.join("\n");
            }
        }
        Edit::SwapLines(a, b) => {
            let mut lines: Vec<String> = text.lines().map(String::from).collect();
            if !lines.is_empty() {
                let (a, b) = (a.index(lines.len()), b.index(lines.len()));
                lines.swap(a, b);
                *text = lines.join("\n");
            }
        }
        Edit::Truncate(i) => {
            let a = at(i, text);
            text.truncate(a);
        }
    }
}

/// Loads `text` as if it were the file `path`: either a scene or an error that names the
/// file; a panic fails the property.
fn load_or_refuse(text: &str, path: &std::path::Path) -> Result<(), TestCaseError> {
    match wgtrace::load_scene_str(text, path, &Overrides::default()) {
        Ok(scene) => {
            prop_assert!(scene.width >= 1 && scene.height >= 1 && scene.spp >= 1);
        }
        Err(e) => {
            let message = e.to_string();
            prop_assert!(
                message.starts_with(&path.display().to_string()),
                "the error does not name the file: {message}"
            );
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// Any bytes at all.
    #[test]
    fn arbitrary_text_is_loaded_or_refused(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let text = String::from_utf8_lossy(&bytes);
        load_or_refuse(&text, &common::repo_path("scenes/fuzz.toml"))?;
    }

    /// Every scene, mutated by one to three edits.
    #[test]
    fn mutated_scenes_are_loaded_or_refused(
        scene in any::<Index>(),
        edits in proptest::collection::vec(edit(), 1..4),
    ) {
        let files = common::scene_files();
        let path = &files[scene.index(files.len())];
        let mut text = std::fs::read_to_string(path).unwrap();
        for e in &edits {
            apply(&mut text, e);
        }
        load_or_refuse(&text, path)?;
    }
}

/// Files too large to read are refused by their size or header before anything is
/// allocated for them: a scene file over 64 MiB, an OBJ over 2 GiB (both sparse files
/// here: no disk used), and an image whose header claims 20000 x 20000 pixels or more
/// texels than a scene may hold. Each error names the file and the limit.
#[test]
fn oversized_files_are_refused_before_they_are_read() {
    use wgtrace::scene::{mesh, textures, MAX_SCENE_FILE_BYTES};
    let dir = common::tmp_dir("fuzz-sizes");
    let sparse = |name: &str, len: u64| {
        let path = dir.join(name);
        std::fs::File::create(&path).unwrap().set_len(len).unwrap();
        path
    };
    let big_scene = sparse("big.toml", MAX_SCENE_FILE_BYTES + 1);
    let e = wgtrace::load_scene(&big_scene, &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("big.toml") && e.contains(&MAX_SCENE_FILE_BYTES.to_string()),
        "{e}"
    );
    sparse("big.obj", mesh::MAX_MESH_FILE_BYTES + 1);
    // a PPM header is the whole of the claim: the pixels are never there
    std::fs::write(dir.join("wide.ppm"), "P6\n20000 8\n255\n").unwrap();
    std::fs::write(dir.join("many.ppm"), "P6\n16384 8193\n255\n").unwrap();
    let head = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials]\n\
                m = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n";
    for (body, key, file, limit) in [
        (
            "[[objects]]\ntype = \"mesh\"\npath = \"big.obj\"\nmaterial = \"m\"\n",
            "objects[0].path",
            "big.obj",
            mesh::MAX_MESH_FILE_BYTES.to_string(),
        ),
        (
            "[textures]\nt = { type = \"image\", path = \"wide.ppm\" }\n",
            "textures.t.path",
            "wide.ppm",
            textures::MAX_TEXTURE_SIDE.to_string(),
        ),
        (
            "[textures]\nt = { type = \"image\", path = \"many.ppm\" }\n",
            "textures.t.path",
            "many.ppm",
            textures::MAX_IMAGE_TEXELS.to_string(),
        ),
    ] {
        let e = wgtrace::load_scene_str(
            &format!("{head}{body}"),
            &dir.join("s.toml"),
            &Overrides::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("s.toml:") && e.contains(key) && e.contains(file) && e.contains(&limit),
            "{e}"
        );
    }
}

//! The checkpoint format's stable parts: the scene hash is FNV-1a, the same on every build,
//! and files of the older format, whose hash was not, are refused with the reason. No GPU
//! needed.

mod common;

use wgtrace::checkpoint::{fnv1a64, scene_hash, Checkpoint, FNV1A64_BASIS, FORMAT};

/// The published FNV-1a 64 test vectors (Fowler, Noll, Vo).
#[test]
fn fnv1a64_gives_the_published_values() {
    assert_eq!(fnv1a64(FNV1A64_BASIS, b""), 0xcbf2_9ce4_8422_2325);
    assert_eq!(fnv1a64(FNV1A64_BASIS, b"a"), 0xaf63_dc4c_8601_ec8c);
    assert_eq!(fnv1a64(FNV1A64_BASIS, b"foobar"), 0x8594_4171_f739_67e8);
    // continuing a hash is hashing the concatenation
    assert_eq!(
        fnv1a64(fnv1a64(FNV1A64_BASIS, b"foo"), b"bar"),
        fnv1a64(FNV1A64_BASIS, b"foobar")
    );
}

const SPHERE: &str = r#"
[render]
width = 4
height = 3
spp = 8
[camera]
look_from = [0, 0, 3]
look_at = [0, 0, 0]
[background]
color = [1, 1, 1]
[materials.grey]
type = "lambertian"
albedo = [0.5, 0.5, 0.5]
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "grey"
"#;

/// A scene's hash is a value pinned here, whatever build computes it (a `DefaultHasher`
/// may change between Rust releases), and it follows what decides the samples: the seed
/// and the records, not the sample count (except for samplers whose points depend on it).
#[test]
fn the_scene_hash_is_the_same_on_every_build() {
    let scene = common::scene_from_str(SPHERE);
    assert_eq!(
        scene_hash(&scene),
        0x8430_ea83_779f_d9d3,
        "the scene hash changed: checkpoints written before are refused as another scene's"
    );
    let with =
        |from: &str, to: &str| scene_hash(&common::scene_from_str(&SPHERE.replace(from, to)));
    assert_eq!(with("spp = 8", "spp = 64"), scene_hash(&scene));
    assert_ne!(with("spp = 8", "spp = 8\nseed = 1"), scene_hash(&scene));
    assert_ne!(with("radius = 1", "radius = 1.5"), scene_hash(&scene));
    let filter = |f: &str| with("spp = 8", &format!("spp = 8\n{f}"));
    assert_ne!(filter("filter = \"tent\""), scene_hash(&scene));
    assert_ne!(filter("filter = \"gaussian\""), filter("filter = \"tent\""));
    assert_ne!(
        filter("filter = \"gaussian\""),
        filter("filter = \"gaussian\"\nfilter_stddev = 0.4")
    );
    let hammersley = |spp: &str| with("spp = 8", &format!("spp = {spp}\nsampler = \"hammersley\""));
    assert_ne!(hammersley("8"), hammersley("64"));
}

/// A checkpoint of an older format (1, no `format` line: its scene hash came from Rust's
/// `DefaultHasher`; 2: its hash left out part of each material record; 3: its parameters
/// held no pixel filter) is refused, saying
/// why, and so is a newer one; the current format round-trips.
#[test]
fn an_older_checkpoint_format_is_refused_with_the_reason() {
    let dir = common::tmp_dir("checkpoint-format");
    let scene = common::scene_from_str(SPHERE);
    let acc = wgtrace::Accumulation {
        width: 4,
        height: 3,
        aovs: false,
        data: vec![[0.5; 4]; 24],
    };
    let path = dir.join("new.ckpt");
    let ckpt = Checkpoint::new(&scene, 0..2, acc);
    ckpt.write(&path).unwrap();
    let read = Checkpoint::read(&path).unwrap();
    assert_eq!(read, ckpt);
    read.check(&scene, 8, &path).unwrap();
    let text = std::fs::read(&path).unwrap();
    assert!(String::from_utf8_lossy(&text).contains(&format!("format = {FORMAT}\n")));

    // (the sums, 0.5 = bytes 00 00 00 3f, are ASCII: the file survives a round trip as text)
    let old = dir.join("old.ckpt");
    let v1 = String::from_utf8_lossy(&text).replace(&format!("format = {FORMAT}\n"), "");
    std::fs::write(&old, v1.as_bytes()).unwrap();
    let err = Checkpoint::read(&old).unwrap_err().to_string();
    assert!(
        err.contains("old.ckpt")
            && err.contains("format 1")
            && err.contains("DefaultHasher")
            && err.contains("render again"),
        "{err}"
    );
    // format 2 hashed only part of each material record
    let two = dir.join("two.ckpt");
    let v2 =
        String::from_utf8_lossy(&text).replace(&format!("format = {FORMAT}\n"), "format = 2\n");
    std::fs::write(&two, v2.as_bytes()).unwrap();
    let err = Checkpoint::read(&two).unwrap_err().to_string();
    assert!(
        err.contains("two.ckpt")
            && err.contains("format 2")
            && err.contains("material record")
            && err.contains("render again"),
        "{err}"
    );
    // format 3 hashed the parameters before they held the pixel filter
    let three = dir.join("three.ckpt");
    let v3 =
        String::from_utf8_lossy(&text).replace(&format!("format = {FORMAT}\n"), "format = 3\n");
    std::fs::write(&three, v3.as_bytes()).unwrap();
    let err = Checkpoint::read(&three).unwrap_err().to_string();
    assert!(
        err.contains("three.ckpt")
            && err.contains("format 3")
            && err.contains("pixel filter")
            && err.contains("render again"),
        "{err}"
    );
    // format 4 hashed the parameters before they held hide_emitters
    let four = dir.join("four.ckpt");
    let v4 =
        String::from_utf8_lossy(&text).replace(&format!("format = {FORMAT}\n"), "format = 4\n");
    std::fs::write(&four, v4.as_bytes()).unwrap();
    let err = Checkpoint::read(&four).unwrap_err().to_string();
    assert!(
        err.contains("format 4") && err.contains("hide_emitters") && err.contains("render again"),
        "{err}"
    );
    // format 5 hashed the light records before their kinds were renumbered
    let five = dir.join("five.ckpt");
    let v5 =
        String::from_utf8_lossy(&text).replace(&format!("format = {FORMAT}\n"), "format = 5\n");
    std::fs::write(&five, v5.as_bytes()).unwrap();
    let err = Checkpoint::read(&five).unwrap_err().to_string();
    assert!(
        err.contains("format 5") && err.contains("primitive's tag") && err.contains("render again"),
        "{err}"
    );
    let newer = dir.join("newer.ckpt");
    let v3 =
        String::from_utf8_lossy(&text).replace(&format!("format = {FORMAT}\n"), "format = 99\n");
    std::fs::write(&newer, v3.as_bytes()).unwrap();
    let err = Checkpoint::read(&newer).unwrap_err().to_string();
    assert!(
        err.contains("format 99") && err.contains("newer wgtrace"),
        "{err}"
    );
}

/// The scene hash sees every byte the renderers read: in a scene with every kind of record
/// (showcase: primitives, materials, lights, BVH nodes, shape data, textures, tables and
/// texel banks), changing one value in any 16-byte region of any record of any array
/// changes the hash, so `--resume` and `merge` refuse samples of a scene that differs
/// there (format 2 hashed only a material's first 96 bytes).
#[test]
fn the_scene_hash_sees_every_region_of_every_record() {
    let scene = wgtrace::load_scene(
        &common::repo_path("scenes/showcase.toml"),
        &wgtrace::scene::load::Overrides::default(),
    )
    .unwrap();
    let base = scene_hash(&scene);
    // (array name, record bytes, a way to reach the array's bytes in a clone)
    type Bytes = fn(&mut wgtrace::FlatScene) -> &mut [u8];
    let arrays: [(&str, usize, Bytes); 7] = [
        ("primitives", 64, |s| {
            bytemuck::cast_slice_mut(&mut s.primitives)
        }),
        (
            "materials",
            std::mem::size_of::<wgtrace::scene::records::Material>(),
            |s| bytemuck::cast_slice_mut(&mut s.materials),
        ),
        (
            "emitters",
            std::mem::size_of::<wgtrace::scene::records::Emitter>(),
            |s| bytemuck::cast_slice_mut(&mut s.emitters),
        ),
        ("bvh", 80, |s| bytemuck::cast_slice_mut(&mut s.bvh)),
        ("shape_data", 16, |s| {
            bytemuck::cast_slice_mut(&mut s.shape_data)
        }),
        (
            "textures",
            std::mem::size_of::<wgtrace::scene::records::Texture>(),
            |s| bytemuck::cast_slice_mut(&mut s.textures),
        ),
        ("tables", 16, |s| bytemuck::cast_slice_mut(&mut s.tables)),
    ];
    let mut pairs = 0;
    for (name, size, bytes) in arrays {
        let n = {
            let mut s = scene.clone();
            bytes(&mut s).len() / size
        };
        assert!(
            n > 0,
            "showcase has no {name}: the test would not cover them"
        );
        // each 16-byte region of the record, in the first and the last record
        for record in [0, n - 1] {
            for region in (0..size).step_by(16) {
                let mut changed = scene.clone();
                let at = record * size + region;
                // the region's last byte: the high byte of its last u32 or f32
                bytes(&mut changed)[at + 15] ^= 0x01;
                assert_ne!(
                    scene_hash(&changed),
                    base,
                    "{name}[{record}] bytes {region}..{}: a change there leaves the hash as it was",
                    region + 16
                );
                pairs += 1;
            }
        }
    }
    let mut changed = scene.clone();
    changed.texels.banks[0].data[0] ^= 1;
    assert_ne!(
        scene_hash(&changed),
        base,
        "a texel's change leaves the hash"
    );
    eprintln!("{pairs} record regions change the hash");
}

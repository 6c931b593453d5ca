//! `wgtrace gallery`: the scenes that show each feature of the original design, rendered to
//! `docs/gallery/` and listed in the README's gallery table with their render times. The
//! list lives here, so the command, the README and the test that checks them agree.

use std::path::Path;

use crate::engine::BackendChoice;
use crate::scene::format::SamplerKind;
use crate::scene::load::Overrides;
use crate::session::{load_scene, Output, Session, SessionError, SessionOptions, StopRule};

/// Samples per pixel of a gallery image unless its entry says otherwise.
pub const GALLERY_SPP: u32 = 256;

/// One gallery image: `scene` (relative to the repository root) rendered at its own size
/// with `spp` (default [`GALLERY_SPP`]) and, where given, another sampler, to
/// `docs/gallery/NAME.png`.
#[derive(Debug, Clone, Copy)]
pub struct Entry {
    pub name: &'static str,
    pub scene: &'static str,
    /// What the image shows, for the table.
    pub shows: &'static str,
    pub sampler: Option<SamplerKind>,
    pub spp: Option<u32>,
    /// A file the scene needs that is too large for the repository, and the arguments to
    /// `cargo` that write it (run when it is missing).
    pub generated: Option<(&'static str, &'static [&'static str])>,
}

const fn entry(name: &'static str, scene: &'static str, shows: &'static str) -> Entry {
    Entry {
        name,
        scene,
        shows,
        sampler: None,
        spp: None,
        generated: None,
    }
}

const fn sampler(name: &'static str, kind: SamplerKind, shows: &'static str) -> Entry {
    Entry {
        name,
        scene: "scenes/cornell.toml",
        shows,
        sampler: Some(kind),
        spp: Some(16),
        generated: None,
    }
}

/// Every gallery image, in the README's order: the original design's shapes, materials,
/// textures, lights and samplers, then transforms, meshes and the showcase.
pub const ENTRIES: &[Entry] = &[
    entry("box", "scenes/box.toml", "Cube: boxes by the slab test"),
    entry(
        "plane",
        "scenes/plane.toml",
        "Plane: a checkered ground to the horizon",
    ),
    entry(
        "spheres",
        "scenes/spheres.toml",
        "Spheres under the gradient sky of Ray Tracing in One Weekend",
    ),
    entry(
        "tetrahedron",
        "scenes/tetrahedron.toml",
        "Triangles and a tetrahedron (watertight triangle test)",
    ),
    entry(
        "cylinder",
        "scenes/cylinder.toml",
        "Finite cylinders, capped and open",
    ),
    entry(
        "pbr",
        "scenes/pbr.toml",
        "glTF metallic-roughness: metallic 0, 0.5, 1 by roughness 0 to 1",
    ),
    entry(
        "gltf-spheres",
        "scenes/gltf-spheres.toml",
        "A glTF file in a scene: metallic 0 to 1 by roughness 0 to 1, its own lights",
    ),
    entry(
        "gltf-brick",
        "scenes/gltf/brick.glb",
        "A .glb on its own: base colour, normal and metallic-roughness textures",
    ),
    entry(
        "punctual",
        "scenes/punctual.toml",
        "Point, spot and directional lights: sharp shadows, glTF's spot falloff",
    ),
    entry(
        "cornell",
        "scenes/cornell.toml",
        "Lambertian: the Cornell box",
    ),
    entry(
        "metal",
        "scenes/metal.toml",
        "Metal: fuzz 0, 0.1, 0.3 and 0.6",
    ),
    entry(
        "dielectric",
        "scenes/dielectric.toml",
        "Dielectric: water, glass, diamond, absorbing glass",
    ),
    entry(
        "microfacet",
        "scenes/microfacet.toml",
        "Microfacet (GGX): roughness 0, 0.05, 0.15, 0.3, 0.5, 1",
    ),
    entry(
        "materials",
        "scenes/materials.toml",
        "Every material side by side",
    ),
    entry(
        "earth",
        "scenes/earth.toml",
        "Image texture: a world map in longitude and latitude",
    ),
    entry(
        "textures",
        "scenes/textures.toml",
        "Checker, Perlin noise, turbulence and marble textures",
    ),
    entry(
        "area-lights",
        "scenes/area-lights.toml",
        "Triangle, polygon and disk lights: soft shadows",
    ),
    entry(
        "disk",
        "scenes/disk.toml",
        "Disks under a tilted disk light",
    ),
    entry(
        "lights",
        "scenes/lights.toml",
        "Sphere, disk and quad lights over a glossy floor",
    ),
    entry(
        "sky",
        "scenes/sky.toml",
        "Environment light: an HDR sky and sun, importance-sampled",
    ),
    sampler(
        "sampler-random",
        SamplerKind::Random,
        "Random sampling, 16 spp",
    ),
    sampler(
        "sampler-jittered",
        SamplerKind::Jittered,
        "Jittered sampling, 16 spp",
    ),
    sampler(
        "sampler-hammersley",
        SamplerKind::Hammersley,
        "Hammersley sampling, 16 spp",
    ),
    entry(
        "transforms",
        "scenes/transforms.toml",
        "Object transforms: scale, rotate, translate",
    ),
    entry("mesh", "scenes/mesh.toml", "OBJ meshes with smooth shading"),
    Entry {
        generated: Some((
            "scenes/large/terrain-100k.obj",
            &[
                "run",
                "--release",
                "--example",
                "gen_mesh",
                "--",
                "heightfield",
                "--triangles",
                "100000",
                "--size",
                "12",
                "--height",
                "1.2",
                "--decimals",
                "5",
                "-o",
                "scenes/large/terrain-100k.obj",
            ],
        )),
        spp: Some(64),
        ..entry(
            "large-mesh",
            "scenes/large/large-mesh.toml",
            "A 100,000-triangle terrain through the BVH",
        )
    },
    Entry {
        spp: Some(64),
        ..entry("showcase", "scenes/showcase.toml", "Everything together")
    },
];

/// The README's gallery lies between these two lines; `wgtrace gallery` rewrites it.
pub const README_START: &str = "<!-- gallery: written by `wgtrace gallery`; do not edit -->";
pub const README_END: &str = "<!-- end of gallery -->";

/// A rendered gallery image, for the table.
#[derive(Debug, Clone)]
pub struct Rendered {
    pub entry: Entry,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seconds: f64,
    /// The adapter that rendered it.
    pub device: String,
    /// Samples dropped as not finite (there should be none).
    pub non_finite: u64,
}

/// Renders `entry` on Vulkan adapter `adapter` to `out/NAME.png`, with `spp` samples per
/// pixel instead of its own when given. A first, one-sample render compiles the shader
/// (lavapipe compiles at the first dispatch), so the seconds are the render's alone.
pub fn render(
    entry: &Entry,
    spp: Option<u32>,
    adapter: usize,
    out: &Path,
) -> Result<Rendered, SessionError> {
    let overrides = Overrides {
        spp: Some(spp.or(entry.spp).unwrap_or(GALLERY_SPP)),
        sampler: entry.sampler,
        ..Default::default()
    };
    let scene = load_scene(Path::new(entry.scene), &overrides)?;
    let opts = SessionOptions {
        backend: BackendChoice::Gpu { adapter },
        ..Default::default()
    };
    let mut warm = scene.clone();
    warm.spp = 1;
    Session::open(warm, opts.clone())?.run(&StopRule::default(), |_| {})?;
    let output = Output {
        image: out.join(format!("{}.png", entry.name)),
        error_map: None,
        preview_every: None,
    };
    let opts = SessionOptions {
        output: Some(output),
        ..opts
    };
    let mut session = Session::open(scene.clone(), opts)?;
    let done = session.run(&StopRule::default(), |_| {})?;
    let acc = &done.accumulation;
    Ok(Rendered {
        entry: *entry,
        width: scene.width,
        height: scene.height,
        spp: scene.spp,
        seconds: done.progress.elapsed.as_secs_f64(),
        device: session.device(),
        non_finite: acc.non_finite(),
    })
}

/// The README's gallery block: a paragraph on how it was made and one table row per image,
/// `image_dir` being the images' folder relative to the README.
pub fn readme_block(rendered: &[Rendered], device: &str, image_dir: &str) -> String {
    let mut s = format!(
        "{README_START}\n\nMade by `cargo run --release -- gallery` (from the repository root) \
         on {device}: each scene at its own size, {GALLERY_SPP} samples per pixel unless the \
         table says otherwise; seconds of rendering, after a one-sample render that compiles \
         the shader.\n\n\
         | image | shows | scene | size, spp | seconds |\n|---|---|---|---|---|\n"
    );
    for r in rendered {
        let e = &r.entry;
        let sampler = match e.sampler {
            Some(kind) => format!(" `--sampler {}`", kind.name()),
            None => String::new(),
        };
        s += &format!(
            "| <img src=\"{image_dir}/{}.png\" width=\"240\" alt=\"{}\"> | {} | [{}]({}){sampler} \
             | {} x {}, {} | {:.1} |\n",
            e.name, e.shows, e.shows, e.scene, e.scene, r.width, r.height, r.spp, r.seconds
        );
    }
    s + "\n" + README_END
}

/// `readme` with its gallery block (from [`README_START`] to [`README_END`]) replaced by
/// `block`; an error when the markers are missing or out of order.
pub fn replace_block(readme: &str, block: &str) -> Result<String, String> {
    let start = readme
        .find(README_START)
        .ok_or_else(|| format!("no line `{README_START}`"))?;
    let end = readme[start..]
        .find(README_END)
        .map(|i| start + i + README_END.len())
        .ok_or_else(|| format!("no line `{README_END}` after `{README_START}`"))?;
    Ok(format!("{}{block}{}", &readme[..start], &readme[end..]))
}

//! The gallery's images: the scenes that show each feature, in the README's order.
//! tests/gallery.rs reads this file too, to hold every scene to an image.

use wgtrace::scene::format::SamplerKind;

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
    // rough glass is found by its own sampling only: more samples for its noise
    Entry {
        spp: Some(1024),
        ..entry(
            "coated",
            "scenes/coated.toml",
            "Rough glass, roughness 0 to 1; a clearcoat, smooth and rough, and a sheen",
        )
    },
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
        "conductors",
        "scenes/conductors.toml",
        "Conductors by measured index: Au, Cu, Ag, Al, Cr; smooth, GGX 0.3, Beckmann 0.6",
    ),
    entry(
        "plastics",
        "scenes/plastics.toml",
        "Plastics: smooth, GGX, Beckmann; linear and nonlinear; a thin-glass window",
    ),
    entry(
        "principled",
        "scenes/principled.toml",
        "Principled (Mitsuba's): metallic, roughness, spec_trans, sheen, clearcoat, anisotropic; 0 to 1",
    ),
    entry(
        "energy",
        "scenes/energy.toml",
        "Energy compensation off and on: gold, a white glTF material, rough glass, a plastic; roughness 0.25 to 1",
    ),
    entry(
        "fog",
        "scenes/fog.toml",
        "Participating media: fog that scatters forward in a null box, a low sun's shaft across it, a glass sphere holding a green medium nested in it",
    ),
    entry(
        "smoke",
        "scenes/smoke.toml",
        "A heterogeneous medium: a smoke plume from a density grid, lit by a low sun under a blue sky, beside a glass ball of cloudy coloured liquid",
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

//! `gen_texture`: writes a world-map-like equirectangular PNG (oceans, continents, ice caps)
//! for the textured-earth scene. The continents are fractal value noise sampled on the unit
//! sphere, so the map has no seam at longitude 180 and no pinch at the poles.
//!
//! ```text
//! cargo run --release --example gen_texture -- scenes/textures/earth.png [WIDTH]
//! ```

use std::f32::consts::PI;

use glam::Vec3;

/// A hash of a lattice point to [0, 1).
fn hash(x: i32, y: i32, z: i32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343)
        ^ (y as u32).wrapping_mul(0xd816_3841)
        ^ (z as u32).wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Trilinear value noise with smoothstep weights, in [0, 1).
fn value_noise(p: Vec3) -> f32 {
    let f = p.floor();
    let t = p - f;
    let s = t * t * (Vec3::splat(3.0) - 2.0 * t);
    let (x, y, z) = (f.x as i32, f.y as i32, f.z as i32);
    let mut acc = 0.0;
    for (dx, dy, dz) in [
        (0, 0, 0),
        (1, 0, 0),
        (0, 1, 0),
        (1, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (0, 1, 1),
        (1, 1, 1),
    ] {
        let w = |d: i32, s: f32| if d == 1 { s } else { 1.0 - s };
        acc += w(dx, s.x) * w(dy, s.y) * w(dz, s.z) * hash(x + dx, y + dy, z + dz);
    }
    acc
}

/// Six octaves of value noise: the elevation field.
fn fbm(p: Vec3) -> f32 {
    let (mut acc, mut amp, mut q) = (0.0, 0.5, p);
    for _ in 0..6 {
        acc += amp * value_noise(q);
        amp *= 0.5;
        q *= 2.03;
    }
    acc
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).map_or("earth.png", String::as_str);
    let width: u32 = args.get(2).and_then(|w| w.parse().ok()).unwrap_or(512);
    let height = width / 2;
    let img = image::RgbImage::from_fn(width, height, |x, y| {
        // longitude and latitude of the pixel centre; v = 0 (the bottom) is the south pole
        let lon = ((x as f32 + 0.5) / width as f32) * 2.0 * PI - PI;
        let lat = PI / 2.0 - ((y as f32 + 0.5) / height as f32) * PI;
        let p = Vec3::new(lat.cos() * lon.cos(), lat.sin(), lat.cos() * lon.sin());
        let e = fbm(2.2 * p + Vec3::new(11.0, 3.0, 7.0));
        let sea = 0.52;
        let c = if lat.abs() > 1.22 + 0.08 * (e - 0.5) {
            [0.93, 0.95, 0.97]
        } else if e < sea {
            mix(
                [0.02, 0.07, 0.25],
                [0.06, 0.28, 0.52],
                (e - 0.3) / (sea - 0.3),
            )
        } else if e < sea + 0.1 {
            mix([0.22, 0.45, 0.16], [0.45, 0.5, 0.25], (e - sea) / 0.1)
        } else {
            mix([0.5, 0.42, 0.28], [0.85, 0.83, 0.8], (e - sea - 0.1) / 0.12)
        };
        image::Rgb(c.map(|v| (v * 255.0).round() as u8))
    });
    img.save(out).expect("write the PNG");
    println!("{out}: {width}x{height}");
}

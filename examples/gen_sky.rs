//! `gen_sky`: writes an equirectangular HDR sky for image backgrounds: a blue sky that
//! brightens toward the horizon, a darker ground below it, and a small sun whose radiance is
//! thousands of times the sky's, the case that needs the background importance-sampled.
//! Row 0 is straight up; the middle column looks along -z (wgtrace's convention).
//!
//! ```text
//! cargo run --release --example gen_sky -- scenes/textures/sky.hdr [WIDTH] [SUN_ELEVATION_DEG] [SUN_AZIMUTH_DEG]
//! ```

use std::f32::consts::PI;

use glam::Vec3;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).map_or("sky.hdr", String::as_str);
    let width: u32 = args.get(2).and_then(|w| w.parse().ok()).unwrap_or(256);
    let elevation: f32 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(35.0);
    let azimuth: f32 = args.get(4).and_then(|a| a.parse().ok()).unwrap_or(40.0);
    let height = width / 2;
    // the sun's direction: azimuth measured from -z toward +x
    let (el, az) = (elevation.to_radians(), azimuth.to_radians());
    let sun = Vec3::new(el.cos() * az.sin(), el.sin(), -el.cos() * az.cos());
    // an angular radius of two texels, so the disk is resolved; radiance set so that the sun
    // gives about 3x the sky's irradiance on a surface facing it
    let radius = 2.0 * PI / height as f32;
    let sun_solid_angle = 2.0 * PI * (1.0 - radius.cos());
    let sun_radiance = 3.0 * PI / sun_solid_angle;
    let img = image::Rgb32FImage::from_fn(width, height, |x, y| {
        let theta = (y as f32 + 0.5) / height as f32 * PI;
        let phi = ((x as f32 + 0.5) / width as f32 - 0.5) * 2.0 * PI;
        let d = Vec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        );
        let c = if d.y >= 0.0 {
            let t = (1.0 - d.y).powi(4);
            let zenith = Vec3::new(0.25, 0.45, 0.95);
            let horizon = Vec3::new(0.95, 0.95, 1.0);
            let glow = Vec3::new(1.0, 0.8, 0.5) * (0.6 * d.dot(sun).max(0.0).powi(16));
            zenith.lerp(horizon, t) + glow
        } else {
            Vec3::new(0.28, 0.24, 0.2) * (0.5 + 0.5 * (1.0 + d.y))
        };
        let angle = d.dot(sun).clamp(-1.0, 1.0).acos();
        // a soft-edged disk: full radiance inside, fading over the last quarter
        let s = ((radius - angle) / (0.25 * radius)).clamp(0.0, 1.0);
        let c = c + Vec3::new(1.0, 0.92, 0.8) * (sun_radiance * s);
        image::Rgb(c.to_array())
    });
    img.save(out).expect("write the HDR image");
    println!("{out}: {width}x{height}, sun radiance {sun_radiance:.0}");
}

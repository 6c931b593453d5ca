//! Mirrors `shaders/materials/blend.wgsl`: a blend has no lobe (its parts are chosen
//! before shading; the defaults absorb, for a record that is never shaded as it is).

use crate::cpu::bindings::Bindings;
use crate::cpu::bsdf::{luminance, Shading};
use crate::cpu::textures::texture_at;
use crate::cpu::types::Hit;
use crate::scene::materials::blend::{Params, MAX_BLEND_DEPTH};
use crate::scene::materials::MaterialKind;
use crate::scene::records::{Material, MAT_FLAG_OWN_COLORS, NO_TEXTURE};

impl Shading for Params {}

/// The record of the material shading a hit on material `index` (blend.wgsl's
/// `blend_choice`): itself, or one of a blend's parts, the second with probability
/// weight, by u reused rescaled within nested blends.
pub fn choice(b: &Bindings, index: u32, hit: &Hit, u: f32) -> Material {
    let mut m = b.materials[index as usize];
    let mut x = u;
    let mut k = 0;
    while k < MAX_BLEND_DEPTH && m.tag == MaterialKind::Blend.tag() {
        let p = Params::read(&m);
        let mut w = p.weight;
        if p.weight_texture != NO_TEXTURE {
            w = luminance(texture_at(b, p.weight_texture, hit)).clamp(0.0, 1.0);
        }
        let own = m.flags & MAT_FLAG_OWN_COLORS;
        if x < w {
            x /= w;
            m = b.materials[p.second as usize];
        } else {
            x = (x - w) / (1.0 - w);
            m = b.materials[p.first as usize];
        }
        m.flags |= own;
        k += 1;
    }
    m
}

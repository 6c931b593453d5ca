// type = "blend": two materials mixed by a weight (scene::materials::blend; CPU twin
// cpu/materials/blend.rs). It has no lobe of its own: blend_choice picks one of its two
// parts at a hit, before material_at, and the path goes on with that one.
#import shared/bindings
#import shared/bsdf
#import shared/textures
#import shared/types

// The record of the material shading a hit on material `index`: itself, or for a blend,
// one of its parts, the second with probability weight (a texture's luminance, clamped to
// [0, 1], where it has one), the first with the rest, by u in [0, 1), reused rescaled for
// a blend within a blend (to MAX_BLEND_DEPTH levels, which validation holds). A blend that
// reads the mesh's colours (MAT_FLAG_OWN_COLORS: its weight a mesh attribute) leaves the
// part it picks untinted by them too.
fn blend_choice(index: u32, hit: Hit, u: f32) -> Material {
    var m = material_record(index);
    var x = u;
    for (var k = 0u; k < MAX_BLEND_DEPTH && m.tag == MAT_BLEND; k++) {
        let p = blend_params(m);
        var w = p.weight;
#ifdef HAS_TEXTURES
        if (p.weight_texture != NO_TEXTURE) {
            w = clamp(luminance(texture_at(p.weight_texture, hit)), 0.0, 1.0);
        }
#endif
        let own = m.flags & MAT_FLAG_OWN_COLORS;
        if (x < w) {
            x = x / w;
            m = material_record(p.second);
        } else {
            x = (x - w) / (1.0 - w);
            m = material_record(p.first);
        }
        m.flags |= own;
    }
    return m;
}

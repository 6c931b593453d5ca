// type = "emissive": a light that absorbs all that reaches it (scene::materials::emissive;
// CPU twin cpu/materials/emissive.rs). Its radiance is the surface's emission. It has no
// lobe, so no function of its own: the dispatch's default absorbs.

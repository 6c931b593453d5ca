//! Mirrors `shaders/materials/emissive.wgsl`: a light has no lobe; it absorbs all that
//! reaches it (the defaults).

use crate::cpu::bsdf::Shading;
use crate::scene::materials::emissive::Params;

impl Shading for Params {}

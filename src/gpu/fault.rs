//! Fault injection (`--tune perturb=PLACES`, `Tuning::perturb`): the GPU side's copy of
//! the records placed in the named placements has one texel of every record changed, as a
//! driver that fetches them wrong would (Mesa 22.3.6's lavapipe on an AVX-512 CPU reads
//! record textures wrong), while the CPU reference keeps the scene as it is. The tests
//! prove with it that the spot check (`crate::spot_check`) sees such a fault, falls back
//! to a safer placement, and refuses the GPU when every placement is wrong.

use super::bindings::{Placements, Slot};
use super::limits::DeviceFit;
use super::plan::GpuPlan;
use crate::scene::flat::FlatScene;
use crate::tuning::Tuning;

/// The plan `tuning` gives `scene` on a device with `fit`, and the scene the device gets:
/// under `tuning.perturb`, a perturbed copy ([`perturb`] of the arrays in the placements
/// the scene's plan gives them), whose plan writes its perturbed records into the shader
/// where the scene's would; else none, and the scene's own plan.
pub fn device_plan(
    scene: &FlatScene,
    fit: &DeviceFit,
    tuning: &Tuning,
) -> (GpuPlan, Option<FlatScene>) {
    let plan = GpuPlan::new(scene, fit, tuning);
    match perturb(scene, &plan.shader.placements, tuning.perturb) {
        Some(p) => (GpuPlan::new(&p, fit, tuning), Some(p)),
        None => (plan, None),
    }
}

/// The arrays a perturbation changes: those that decide what a ray hits and how the
/// surface looks (the two that may be textures, and the materials, which may be in the
/// shader or a uniform buffer).
const PERTURBED: [Slot; 3] = [Slot::Primitives, Slot::Bvh, Slot::Materials];

/// `scene` with one texel of every record of each array in [`PERTURBED`] whose placement
/// is among `places` (bits of `tuning::PLACEMENT_NAMES`) changed: a primitive's first
/// shape vector (a triangle's first corner, a sphere's centre, a plane's point) moved, a
/// BVH node's grid origin moved past the scene (every box it holds missed), a material's
/// colour changed. None when no array is in those placements.
pub fn perturb(scene: &FlatScene, placements: &Placements, places: u8) -> Option<FlatScene> {
    let hit = |slot: Slot| places & placements.get(slot).bit() != 0;
    if !PERTURBED.into_iter().any(hit) {
        return None;
    }
    let mut s = scene.clone();
    if hit(Slot::Primitives) {
        for p in &mut s.primitives {
            p.a[0] += 0.5 * (1.0 + p.a[0].abs());
        }
    }
    if hit(Slot::Bvh) {
        for n in &mut s.bvh {
            n.origin[0] += 1e6;
        }
    }
    if hit(Slot::Materials) {
        for m in &mut s.materials {
            for c in &mut m.color[..3] {
                *c = 0.5 * *c + 0.3;
            }
        }
    }
    Some(s)
}

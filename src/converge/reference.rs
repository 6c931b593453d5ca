//! The reference image a study measures against: given by the user, left by an earlier
//! study of the same scene, size and path length (`reference.exr` with `reference.toml`),
//! or rendered with the Sobol' sampler and MIS at many samples.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::error::{file_err, ConvergeError};
use super::options::{Event, Options};
use super::results::ReferenceInfo;
use crate::engine::BackendChoice;
use crate::scene::flat::FlatScene;
use crate::scene::format::{LightSampling, SamplerKind};
use crate::scene::load::Overrides;
use crate::session::{load_scene, Finished, Session, SessionOptions, StopRule};

const REFERENCE_SEED: u32 = 0x5eed_0000;

pub(super) fn load(scene: &Path, overrides: &Overrides) -> Result<FlatScene, ConvergeError> {
    Ok(load_scene(scene, overrides)?)
}

/// A session rendering `scene` on `backend`, writing nothing.
pub(super) fn session(scene: FlatScene, backend: BackendChoice) -> Result<Session, ConvergeError> {
    Ok(Session::open(
        scene,
        SessionOptions {
            backend,
            ..Default::default()
        },
    )?)
}

/// The reference image (linear RGB), rendered or read, and what it is.
pub fn reference(
    opts: &Options,
    max_depth: u32,
    mut event: impl FnMut(Event),
) -> Result<(Vec<f32>, ReferenceInfo, PathBuf), ConvergeError> {
    let probe = load(&opts.scene, &opts.overrides)?;
    if let Some(path) = &opts.reference {
        let rgb = given_reference(path, &probe)?;
        let info = ReferenceInfo {
            scene: opts.scene.display().to_string(),
            width: probe.width,
            height: probe.height,
            spp: 0,
            seed: 0,
            max_depth: 0,
            sampler: "given".into(),
            light_sampling: "given".into(),
            backend: "given".into(),
            seconds: 0.0,
            est_rel_mse: 0.0,
        };
        event(Event::ReferenceReady { path, cached: true });
        return Ok((rgb, info, path.clone()));
    }
    let exr = opts.out.join("reference.exr");
    let meta = opts.out.join("reference.toml");
    if let Some((rgb, info)) = cached_reference(opts, &probe, max_depth)? {
        event(Event::ReferenceReady {
            path: &exr,
            cached: true,
        });
        return Ok((rgb, info, exr));
    }
    let overrides = Overrides {
        spp: Some(opts.reference_spp),
        seed: Some(REFERENCE_SEED),
        max_depth: Some(max_depth),
        sampler: Some(SamplerKind::Sobol),
        light_sampling: Some(LightSampling::Mis),
        ..opts.overrides.clone()
    };
    let scene = load(&opts.scene, &overrides)?;
    let mut session = session(scene.clone(), opts.reference_backend)?;
    if let Some(note) = session.note() {
        event(Event::Note(note));
    }
    let start = Instant::now();
    let Finished {
        accumulation: acc, ..
    } = session.run(&StopRule::default(), |p| {
        event(Event::Reference {
            spp: scene.spp,
            done: p.passes_done,
        })
    })?;
    let seconds = start.elapsed().as_secs_f64();
    let rgb = acc.to_rgb();
    crate::image_io::write_image(&exr, scene.width, scene.height, &rgb)?;
    let info = ReferenceInfo {
        scene: opts.scene.display().to_string(),
        width: scene.width,
        height: scene.height,
        spp: scene.spp,
        seed: REFERENCE_SEED,
        max_depth,
        sampler: "sobol".into(),
        light_sampling: "mis".into(),
        backend: session.device(),
        seconds,
        est_rel_mse: acc.estimated_rel_mse(),
    };
    let text = toml::to_string(&info).map_err(|e| file_err(&meta, e))?;
    std::fs::write(&meta, text).map_err(|e| file_err(&meta, e))?;
    event(Event::ReferenceReady {
        path: &exr,
        cached: false,
    });
    Ok((rgb, info, exr))
}

/// A reference EXR the user gave, which must have the renders' size.
fn given_reference(path: &Path, probe: &FlatScene) -> Result<Vec<f32>, ConvergeError> {
    let img = crate::scene::textures::load_image(path, true).map_err(|e| file_err(path, e))?;
    if (img.width, img.height) != (probe.width, probe.height) {
        return Err(file_err(
            path,
            format!(
                "is {}x{}, the renders are {}x{} (set --width and --height to match)",
                img.width, img.height, probe.width, probe.height
            ),
        ));
    }
    Ok(img
        .linear()
        .iter()
        .flat_map(|t| [t[0], t[1], t[2]])
        .collect())
}

/// The reference an earlier study left in the output folder, when it was rendered for
/// this scene, size and path length with at least the samples asked for.
fn cached_reference(
    opts: &Options,
    probe: &FlatScene,
    max_depth: u32,
) -> Result<Option<(Vec<f32>, ReferenceInfo)>, ConvergeError> {
    let exr = opts.out.join("reference.exr");
    let meta = opts.out.join("reference.toml");
    let (Ok(text), true) = (std::fs::read_to_string(&meta), exr.exists()) else {
        return Ok(None);
    };
    let Ok(info) = toml::from_str::<ReferenceInfo>(&text) else {
        return Ok(None);
    };
    let wanted = info.scene == opts.scene.display().to_string()
        && (info.width, info.height) == (probe.width, probe.height)
        && info.max_depth == max_depth
        && info.spp >= opts.reference_spp;
    if !wanted {
        return Ok(None);
    }
    let img = crate::scene::textures::load_image(&exr, true).map_err(|e| file_err(&exr, e))?;
    let rgb = img
        .linear()
        .iter()
        .flat_map(|t| [t[0], t[1], t[2]])
        .collect();
    Ok(Some((rgb, info)))
}

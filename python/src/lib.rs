//! `wgtrace._wgtrace`: the renderer from Python. A scene file is loaded once
//! ([`Scene`], with the command line's overrides as keywords) and rendered any number of
//! times into numpy arrays, through the same session as `wgtrace render`, so the pixels
//! are the CLI's, bit for bit on the same backend. The GIL is released while a render
//! runs; after each batch of passes the progress callback runs and Ctrl-C is looked for
//! (KeyboardInterrupt then ends the render). Every process opens one device per adapter
//! and reuses it (`GpuContext::shared`). Sample ranges render into [`Sums`], which merge
//! as `wgtrace merge` does and pickle, for Ray and other schedulers.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use numpy::{PyArray1, PyArrayMethods};
use pyo3::conversion::FromPyObjectOwned;
use pyo3::create_exception;
use pyo3::exceptions::{
    PyKeyboardInterrupt, PyOverflowError, PyRuntimeError, PyTypeError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use wgtrace::aov::{check_output, image_layers, write_output, Aov, OutputError};
use wgtrace::checkpoint::Checkpoint;
use wgtrace::denoise::Denoiser;
use wgtrace::image_io::Layer;
use wgtrace::scene::format::{FilterKind, LightSampling, SamplerKind};
use wgtrace::session::{Passes, Session, SessionError, SessionOptions, StopRule};
use wgtrace::{BackendChoice, FlatScene, Overrides};

create_exception!(
    _wgtrace,
    WgtraceError,
    PyRuntimeError,
    "A render that failed: no device, a lost device, a checkpoint that does not fit."
);
create_exception!(
    _wgtrace,
    SceneError,
    PyValueError,
    "A scene file that cannot be read or is wrong; the message names the file, and the line \
     and key (or the JSON path) of each problem, as `wgtrace render` prints it."
);
create_exception!(
    _wgtrace,
    DenoiseError,
    WgtraceError,
    "Open Image Denoise is missing or failed (`pip install pyoidn`)."
);

/// A loaded scene: its records, ready to render any number of times.
#[pyclass(module = "wgtrace", frozen)]
struct Scene {
    scene: FlatScene,
    path: PathBuf,
}

/// Sums of samples of one scene over sample ranges: what a render holds before it becomes
/// an image. Merged with `wgtrace.merge`, saved as a checkpoint `wgtrace merge` and
/// `wgtrace render --resume` read, and pickled whole.
#[pyclass(module = "wgtrace", frozen)]
struct Sums {
    ckpt: Checkpoint,
}

fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(e.to_string())
}

/// A session's failure as a Python exception: a scene's problem as SceneError, a missing
/// denoiser as DenoiseError, anything else as WgtraceError.
fn session_error(e: SessionError) -> PyErr {
    match e {
        SessionError::Scene(e) => scene_error(e),
        SessionError::Denoise(e) => DenoiseError::new_err(e.to_string()),
        SessionError::Output(e) => output_error(e),
        e => WgtraceError::new_err(e.to_string()),
    }
}

/// A keyword's value as `T` (None when absent or None), or TypeError naming the keyword
/// and what it takes (ValueError for a number out of the type's range).
fn arg<'py, T: FromPyObjectOwned<'py>>(
    name: &str,
    what: &str,
    v: Option<&Bound<'py, PyAny>>,
) -> PyResult<Option<T>> {
    let Some(x) = v.filter(|x| !x.is_none()) else {
        return Ok(None);
    };
    x.extract::<T>().map(Some).map_err(|e| {
        let e: PyErr = e.into();
        let got = x
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        if e.is_instance_of::<PyOverflowError>(x.py()) {
            PyValueError::new_err(format!("{name}={x}: out of range for {what}"))
        } else {
            PyTypeError::new_err(format!("{name}: expected {what}, got {got}"))
        }
    })
}

/// A keyword's value out of a list of names, or ValueError naming the keyword.
fn choice<T: clap::ValueEnum>(key: &str, value: Option<&str>) -> PyResult<Option<T>> {
    value
        .map(|v| {
            T::from_str(v, true).map_err(|_| {
                let names: Vec<String> = T::value_variants()
                    .iter()
                    .filter_map(|x| x.to_possible_value().map(|p| p.get_name().to_string()))
                    .collect();
                PyValueError::new_err(format!("{key}={v:?}: expected one of {}", names.join(", ")))
            })
        })
        .transpose()
}

fn rgb(key: &str, v: Option<Vec<f32>>) -> PyResult<Option<[f32; 3]>> {
    v.map(|c| match c[..] {
        [r, g, b] if c.iter().all(|x| x.is_finite() && *x >= 0.0) => Ok([r, g, b]),
        _ => Err(PyValueError::new_err(format!(
            "{key}={c:?}: expected three numbers >= 0 (r, g, b)"
        ))),
    })
    .transpose()
}

fn aov_list(aovs: Option<Vec<String>>) -> PyResult<Vec<Aov>> {
    let names = aovs.unwrap_or_default();
    let mut out = Vec::new();
    for n in &names {
        let a = Aov::from_name(n).map_err(|e| PyValueError::new_err(format!("aovs: {e}")))?;
        if out.contains(&a) {
            return Err(PyValueError::new_err(format!("aovs: {n:?} is named twice")));
        }
        out.push(a);
    }
    Ok(out)
}

/// The backend and adapter: "gpu" (the adapter `adapter` names, an index or part of a
/// name, else the one a scheduler assigned, as the CLI chooses) or "cpu".
fn backend(
    py: Python<'_>,
    backend: &str,
    adapter: Option<&Bound<'_, PyAny>>,
) -> PyResult<BackendChoice> {
    let arg = match adapter {
        None => None,
        Some(a) => Some(if let Ok(i) = a.extract::<usize>() {
            i.to_string()
        } else if let Ok(s) = a.extract::<String>() {
            s
        } else {
            return Err(PyTypeError::new_err(
                "adapter: expected an index (int) or part of an adapter's name (str)",
            ));
        }),
    };
    match backend {
        "gpu" => {
            let s = py
                .detach(|| wgtrace::gpu::context::select_adapter(arg.as_deref()))
                .map_err(|e| WgtraceError::new_err(e.to_string()))?;
            Ok(BackendChoice::Gpu { adapter: s.index })
        }
        "cpu" if arg.is_some() => Err(PyValueError::new_err(
            "adapter: given with backend=\"cpu\", which has none",
        )),
        "cpu" => Ok(BackendChoice::Cpu),
        other => Err(PyValueError::new_err(format!(
            "backend={other:?}: expected \"gpu\" or \"cpu\""
        ))),
    }
}

fn sample_range(samples: Option<(u32, u32)>) -> PyResult<Option<Range<u32>>> {
    samples
        .map(|(a, b)| {
            if b > a {
                Ok(a..b)
            } else {
                Err(PyValueError::new_err(format!(
                    "samples=({a}, {b}): the end must exceed the start"
                )))
            }
        })
        .transpose()
}

/// Renders `scene` over `range` (its own samples when None) on `choice`, the GIL
/// released, calling `progress(done, total)` and looking for Ctrl-C after each batch.
#[allow(clippy::too_many_arguments)]
fn run(
    py: Python<'_>,
    scene: FlatScene,
    choice: BackendChoice,
    range: Option<Range<u32>>,
    aovs: bool,
    resume: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Checkpoint> {
    let mut scene = scene;
    scene.aovs = aovs;
    let passes = match &range {
        Some(r) => Passes::Range(r.clone()),
        None => Passes::Scene,
    };
    let opts = SessionOptions {
        backend: choice,
        cpu_fallback: true,
        passes,
        resume,
        ..Default::default()
    };
    let interrupt = Arc::new(AtomicBool::new(false));
    let rule = StopRule {
        interrupt: Some(interrupt.clone()),
        ..Default::default()
    };
    // the first error of the callback or of Ctrl-C, raised once the render has stopped
    let raised: Mutex<Option<PyErr>> = Mutex::new(None);
    let result = py.detach(|| {
        let mut session = Session::open(scene, opts)?;
        if let Some(note) = session.note() {
            eprintln!("wgtrace: {note}");
        }
        let start = session.range().start;
        let finished = session.run(&rule, |p| {
            Python::attach(|py| {
                let step = py.check_signals().and_then(|_| match &progress {
                    Some(cb) => cb
                        .call1(py, (p.passes_done - start, p.passes_total - start))
                        .map(|_| ()),
                    None => Ok(()),
                });
                if let Err(e) = step {
                    raised.lock().expect("not poisoned").get_or_insert(e);
                    interrupt.store(true, Ordering::SeqCst);
                }
            })
        });
        let range = session.range();
        finished.map(|done| {
            let end = done.progress.passes_done;
            Checkpoint::new(session.scene(), range.start..end, done.accumulation)
        })
    });
    if let Some(e) = raised.lock().expect("not poisoned").take() {
        return Err(e);
    }
    match result {
        Ok(c) => Ok(c),
        Err(SessionError::Interrupted { .. }) => Err(PyKeyboardInterrupt::new_err(())),
        Err(e) => Err(session_error(e)),
    }
}

/// The denoiser when `denoise` asks for it.
fn denoiser_if(py: Python<'_>, denoise: bool) -> PyResult<Option<&'static Denoiser>> {
    denoise.then(|| load_denoiser(py)).transpose()
}

/// An image that cannot be made or written, as a Python exception: what the caller asked
/// wrongly as ValueError, a denoiser's failure as DenoiseError, a file's as WgtraceError.
fn output_error(e: OutputError) -> PyErr {
    match e {
        OutputError::NotExr(_) | OutputError::NoAovSums => PyValueError::new_err(e.to_string()),
        OutputError::Denoise(e) => DenoiseError::new_err(e.to_string()),
        OutputError::Image(e) => WgtraceError::new_err(e.to_string()),
    }
}

/// The process's denoiser, from this interpreter's pyoidn, else as the CLI finds it.
fn load_denoiser(py: Python<'_>) -> PyResult<&'static Denoiser> {
    let dir = pyoidn_dir(py);
    py.detach(|| Denoiser::shared_with(dir.as_deref()))
        .map_err(|e| DenoiseError::new_err(e.to_string()))
}

/// The layers of finished sums as a dict of float32 arrays: "color" (H, W, 3), then each
/// AOV ((H, W) for depth); with `denoise`, "color" denoised and "noisy" beside it.
fn image_dict<'py>(
    py: Python<'py>,
    ckpt: &Checkpoint,
    aovs: &[Aov],
    denoise: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let acc = &ckpt.accumulation;
    let denoiser = denoiser_if(py, denoise)?;
    let layers = py
        .detach(|| image_layers(acc, aovs, denoiser))
        .map_err(output_error)?;
    let dict = PyDict::new(py);
    for layer in layers {
        let key = if layer.name.is_empty() {
            "color".to_string()
        } else {
            layer.name.clone()
        };
        dict.set_item(key, layer_array(py, acc.width, acc.height, layer)?)?;
    }
    Ok(dict)
}

/// A layer as a float32 array of (H, W, channels), or (H, W) for one channel.
fn layer_array<'py>(
    py: Python<'py>,
    width: u32,
    height: u32,
    layer: Layer,
) -> PyResult<Bound<'py, PyAny>> {
    let k = layer.channels.len();
    let (h, w) = (height as usize, width as usize);
    let flat = PyArray1::from_vec(py, layer.values);
    let shaped = if k == 1 {
        flat.reshape([h, w])?.into_any()
    } else {
        flat.reshape([h, w, k])?.into_any()
    };
    Ok(shaped)
}

/// Where the interpreter running this module would import `pyoidn` from, if it is
/// installed: the wheel ships libOpenImageDenoise in its `oidn/lib`.
fn pyoidn_dir(py: Python<'_>) -> Option<PathBuf> {
    let util = py.import("importlib.util").ok()?;
    let spec = util.call_method1("find_spec", ("pyoidn",)).ok()?;
    if spec.is_none() {
        return None;
    }
    let locations = spec.getattr("submodule_search_locations").ok()?;
    let first = locations.get_item(0).ok()?;
    first.extract::<String>().ok().map(PathBuf::from)
}

#[pymethods]
impl Scene {
    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.scene.width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.scene.height
    }

    /// Samples per pixel a render takes unless told otherwise.
    #[getter]
    fn spp(&self) -> u32 {
        self.scene.spp
    }

    /// The scene file.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// What the loader left out or approximated (a glTF file's unsupported parts), one
    /// line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "wgtrace.Scene({:?}, {}x{}, {} spp, {} primitives)",
            self.path.display().to_string(),
            self.scene.width,
            self.scene.height,
            self.scene.spp,
            self.scene.primitives.len()
        )
    }

    /// Renders the scene: a dict of float32 arrays, "color" (H, W, 3: linear radiance)
    /// and each AOV asked for ("albedo", "normal", "position", "variance": (H, W, 3);
    /// "depth": (H, W)). `spp` and `seed` replace the scene's; `samples=(start, end)`
    /// renders those sample indices only (end at most spp); `denoise` runs Open Image
    /// Denoise on "color" (the noisy one then under "noisy"); `progress(done, total)` is
    /// called after each batch of passes; `backend` is "gpu" or "cpu"; `adapter` an index
    /// or part of a name (default: the GPU a scheduler assigned, else the first).
    #[pyo3(signature = (*, spp=None, seed=None, aovs=None, denoise=None, samples=None, progress=None, backend=None, adapter=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        spp: Option<&Bound<'py, PyAny>>,
        seed: Option<&Bound<'py, PyAny>>,
        aovs: Option<&Bound<'py, PyAny>>,
        denoise: Option<&Bound<'py, PyAny>>,
        samples: Option<&Bound<'py, PyAny>>,
        progress: Option<Py<PyAny>>,
        backend: Option<&Bound<'py, PyAny>>,
        adapter: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let aovs = aov_list(arg("aovs", "a list of AOV names", aovs)?)?;
        let denoise = arg("denoise", "a bool", denoise)?.unwrap_or(false);
        let how = How::parse(spp, seed, samples, backend)?;
        if denoise {
            // a missing denoiser fails now, not after the render
            load_denoiser(py)?;
        }
        let summed = denoise || aovs.iter().any(|a| a.summed());
        let sums = self.sums(py, how, summed, progress, adapter)?;
        image_dict(py, &sums.ckpt, &aovs, denoise)
    }

    /// Renders sample indices `samples=(start, end)` (default: all the scene's) into Sums,
    /// to merge with others (`wgtrace.merge`) and turn into an image later. `aovs=True`
    /// keeps the AOVs' sums (needed for AOVs and denoising of the merged image).
    #[pyo3(signature = (*, samples=None, spp=None, seed=None, aovs=None, progress=None, backend=None, adapter=None))]
    #[allow(clippy::too_many_arguments)]
    fn accumulate<'py>(
        &self,
        py: Python<'py>,
        samples: Option<&Bound<'py, PyAny>>,
        spp: Option<&Bound<'py, PyAny>>,
        seed: Option<&Bound<'py, PyAny>>,
        aovs: Option<&Bound<'py, PyAny>>,
        progress: Option<Py<PyAny>>,
        backend: Option<&Bound<'py, PyAny>>,
        adapter: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Sums> {
        let aovs = arg("aovs", "a bool", aovs)?.unwrap_or(false);
        let how = How::parse(spp, seed, samples, backend)?;
        self.sums(py, how, aovs, progress, adapter)
    }
}

/// The keywords `Scene.render` and `Scene.accumulate` share: what to render, and where.
struct How {
    spp: Option<u32>,
    seed: Option<u32>,
    samples: Option<(u32, u32)>,
    backend: String,
}

impl How {
    fn parse<'py>(
        spp: Option<&Bound<'py, PyAny>>,
        seed: Option<&Bound<'py, PyAny>>,
        samples: Option<&Bound<'py, PyAny>>,
        backend: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<How> {
        Ok(How {
            spp: arg("spp", "an int", spp)?,
            seed: arg("seed", "an int", seed)?,
            samples: arg("samples", "a (start, end) pair of ints", samples)?,
            backend: arg("backend", "\"gpu\" or \"cpu\"", backend)?.unwrap_or("gpu".into()),
        })
    }
}

impl Scene {
    fn sums<'py>(
        &self,
        py: Python<'py>,
        how: How,
        aovs: bool,
        progress: Option<Py<PyAny>>,
        adapter: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Sums> {
        let How {
            spp,
            seed,
            samples,
            backend: backend_name,
        } = how;
        let mut scene = self.scene.clone();
        if let Some(n) = spp {
            if !(1..=wgtrace::scene::MAX_SPP).contains(&n) {
                return Err(PyValueError::new_err(format!(
                    "spp={n}: expected 1 to {}",
                    wgtrace::scene::MAX_SPP
                )));
            }
            scene.spp = n;
        }
        if let Some(s) = seed {
            scene.seed = s;
        }
        let range = sample_range(samples)?;
        if let Some(r) = &range {
            if r.end > scene.spp {
                return Err(PyValueError::new_err(format!(
                    "samples=({}, {}): ends past the render's {} samples per pixel (spp)",
                    r.start, r.end, scene.spp
                )));
            }
        }
        if let Some(cb) = &progress {
            if !cb.bind(py).is_callable() {
                return Err(PyTypeError::new_err(
                    "progress: expected a callable progress(done, total)",
                ));
            }
        }
        let choice = backend(py, &backend_name, adapter)?;
        let ckpt = run(py, scene, choice, range, aovs, None, progress)?;
        Ok(Sums { ckpt })
    }
}

#[pymethods]
impl Sums {
    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.ckpt.accumulation.width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.ckpt.accumulation.height
    }

    /// The sample index ranges held, as (start, end) pairs.
    #[getter]
    fn samples(&self) -> Vec<(u32, u32)> {
        self.ckpt.samples.iter().map(|r| (r.start, r.end)).collect()
    }

    /// Whether the sums hold the AOVs.
    #[getter]
    fn aovs(&self) -> bool {
        self.ckpt.accumulation.aovs
    }

    fn __repr__(&self) -> String {
        format!(
            "wgtrace.Sums({}x{}, samples {:?}, aovs {})",
            self.width(),
            self.height(),
            self.samples(),
            self.aovs()
        )
    }

    /// The image: a dict as `Scene.render` returns it.
    #[pyo3(signature = (*, aovs=None, denoise=None))]
    fn image<'py>(
        &self,
        py: Python<'py>,
        aovs: Option<&Bound<'py, PyAny>>,
        denoise: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let aovs = aov_list(arg("aovs", "a list of AOV names", aovs)?)?;
        let denoise = arg("denoise", "a bool", denoise)?.unwrap_or(false);
        image_dict(py, &self.ckpt, &aovs, denoise)
    }

    /// Writes the image to `path` as `wgtrace merge` does: .exr with the AOVs as layers
    /// (`albedo.R`, ...; the noisy colour as `noisy` when denoised), .png or .ppm with the
    /// colour only.
    #[pyo3(signature = (path, *, aovs=None, denoise=None))]
    fn write_image<'py>(
        &self,
        py: Python<'py>,
        path: PathBuf,
        aovs: Option<&Bound<'py, PyAny>>,
        denoise: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<()> {
        let aovs = aov_list(arg("aovs", "a list of AOV names", aovs)?)?;
        let denoise = arg("denoise", "a bool", denoise)?.unwrap_or(false);
        check_output(&path, &aovs).map_err(output_error)?;
        let denoiser = denoiser_if(py, denoise)?;
        let acc = &self.ckpt.accumulation;
        py.detach(|| write_output(&path, acc, &aovs, denoiser))
            .map_err(output_error)
    }

    /// Writes the sums as a checkpoint file (`wgtrace merge` and `render --resume` read it).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.ckpt
            .write(&path)
            .map_err(|e| WgtraceError::new_err(format!("{}: {e}", path.display())))
    }

    /// Reads a checkpoint file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Sums> {
        Checkpoint::read(&path)
            .map(|ckpt| Sums { ckpt })
            .map_err(|e| WgtraceError::new_err(e.to_string()))
    }

    /// The checkpoint file's bytes.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.ckpt.to_bytes())
    }

    /// Sums from `to_bytes`.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Sums> {
        Checkpoint::from_bytes(data, Path::new("<bytes>"))
            .map(|ckpt| Sums { ckpt })
            .map_err(|e| WgtraceError::new_err(e.to_string()))
    }

    /// Pickled as its bytes.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let from = py.get_type::<Sums>().getattr("from_bytes")?;
        Ok((from, (slf.get().to_bytes(py),)))
    }
}

/// Loads a scene file: TOML, or a glTF 2.0 file (.gltf, .glb) on its own. The keywords are
/// the command line's overrides.
#[pyfunction]
#[pyo3(signature = (path, *, width=None, height=None, spp=None, max_depth=None, seed=None, sampler=None, light_sampling=None, filter=None, background=None, camera=None, energy_compensation=None))]
#[allow(clippy::too_many_arguments)]
fn load<'py>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
    width: Option<&Bound<'py, PyAny>>,
    height: Option<&Bound<'py, PyAny>>,
    spp: Option<&Bound<'py, PyAny>>,
    max_depth: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    sampler: Option<&Bound<'py, PyAny>>,
    light_sampling: Option<&Bound<'py, PyAny>>,
    filter: Option<&Bound<'py, PyAny>>,
    background: Option<&Bound<'py, PyAny>>,
    camera: Option<&Bound<'py, PyAny>>,
    energy_compensation: Option<&Bound<'py, PyAny>>,
) -> PyResult<Scene> {
    let path: PathBuf = arg("path", "a path (str or os.PathLike)", Some(path))?
        .ok_or_else(|| PyTypeError::new_err("path: expected a path, got None"))?;
    let int = |name, v| arg::<u32>(name, "an int >= 0", v);
    let sampler: Option<String> = arg("sampler", "a str", sampler)?;
    let light_sampling: Option<String> = arg("light_sampling", "a str", light_sampling)?;
    let filter: Option<String> = arg("filter", "a str", filter)?;
    let overrides = Overrides {
        width: int("width", width)?,
        height: int("height", height)?,
        spp: int("spp", spp)?,
        max_depth: int("max_depth", max_depth)?,
        seed: int("seed", seed)?,
        sampler: choice::<SamplerKind>("sampler", sampler.as_deref())?,
        light_sampling: choice::<LightSampling>("light_sampling", light_sampling.as_deref())?,
        filter: choice::<FilterKind>("filter", filter.as_deref())?,
        background: rgb(
            "background",
            arg("background", "three numbers (r, g, b)", background)?,
        )?,
        camera: arg("camera", "a camera's name (str)", camera)?,
        energy_compensation: arg::<bool>("energy_compensation", "a bool", energy_compensation)?
            .unwrap_or(false),
        defines: Vec::new(),
    };
    let scene = py
        .detach(|| wgtrace::load_scene(&path, &overrides))
        .map_err(scene_error)?;
    Ok(Scene { scene, path })
}

/// Adds up Sums of one scene over disjoint sample ranges (objects or checkpoint paths), as
/// `wgtrace merge` does.
#[pyfunction]
fn merge(parts: &Bound<'_, PyList>) -> PyResult<Sums> {
    let mut list = Vec::new();
    for (i, item) in parts.iter().enumerate() {
        if let Ok(s) = item.cast::<Sums>() {
            list.push((PathBuf::from(format!("parts[{i}]")), s.get().ckpt.clone()));
        } else if let Ok(p) = item.extract::<PathBuf>() {
            let c = Checkpoint::read(&p).map_err(|e| WgtraceError::new_err(e.to_string()))?;
            list.push((p, c));
        } else {
            return Err(PyTypeError::new_err(format!(
                "merge: parts[{i}] is neither Sums nor a checkpoint path"
            )));
        }
    }
    Checkpoint::merge(&list)
        .map(|ckpt| Sums { ckpt })
        .map_err(|e| WgtraceError::new_err(e.to_string()))
}

/// The Vulkan adapters, in the order `adapter=` counts them: dicts of name, device type,
/// PCI bus id and UUID.
#[pyfunction]
fn adapters(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    let infos = py.detach(wgtrace::gpu::list_adapters);
    let facts = py.detach(wgtrace::gpu::context::adapter_facts);
    infos
        .iter()
        .zip(&facts)
        .map(|(info, f)| {
            let d = PyDict::new(py);
            d.set_item("name", &info.name)?;
            d.set_item("device_type", format!("{:?}", info.device_type))?;
            d.set_item("driver", format!("{} {}", info.driver, info.driver_info))?;
            d.set_item("pci_bus_id", &f.pci_bus_id)?;
            d.set_item("uuid", f.uuid.map(wgtrace::gpu::select::format_uuid))?;
            Ok(d)
        })
        .collect()
}

/// Every channel of an EXR file, grouped into layers: {"color": R, G, B; "albedo":
/// albedo.R, G, B; "depth": depth.Z, ...} as float32 arrays (H, W, channels), or (H, W)
/// for a layer of one channel.
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let exr =
        wgtrace::image_io::read_exr(&path).map_err(|e| WgtraceError::new_err(e.to_string()))?;
    // channels by layer, in the conventional order of their names
    let order = |c: &str| {
        ["R", "G", "B", "A", "X", "Y", "Z"]
            .iter()
            .position(|x| *x == c)
            .unwrap_or(usize::MAX)
    };
    type Channels = Vec<(String, Vec<f32>)>;
    let mut groups: Vec<(String, Channels)> = Vec::new();
    for (name, values) in exr.channels {
        let (layer, channel) = match name.rsplit_once('.') {
            Some((l, c)) => (l.to_string(), c.to_string()),
            None => ("color".to_string(), name.clone()),
        };
        match groups.iter_mut().find(|(l, _)| *l == layer) {
            Some((_, chans)) => chans.push((channel, values)),
            None => groups.push((layer, vec![(channel, values)])),
        }
    }
    let dict = PyDict::new(py);
    let n = exr.width as usize * exr.height as usize;
    for (layer, mut chans) in groups {
        chans.sort_by(|a, b| order(&a.0).cmp(&order(&b.0)).then(a.0.cmp(&b.0)));
        let k = chans.len();
        if let Some((c, v)) = chans.iter().find(|(_, v)| v.len() != n) {
            return Err(WgtraceError::new_err(format!(
                "{}: channel {layer}.{c} holds {} values, the image {n}",
                path.display(),
                v.len()
            )));
        }
        let mut values = vec![0.0f32; n * k];
        for (c, (_, v)) in chans.iter().enumerate() {
            for (i, x) in v.iter().enumerate() {
                values[i * k + c] = *x;
            }
        }
        let l = Layer {
            name: layer.clone(),
            channels: chans.into_iter().map(|(c, _)| c).collect(),
            values,
        };
        dict.set_item(layer, layer_array(py, exr.width, exr.height, l)?)?;
    }
    Ok(dict)
}

#[pymodule]
fn _wgtrace(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Sums>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(adapters, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add("WgtraceError", m.py().get_type::<WgtraceError>())?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("DenoiseError", m.py().get_type::<DenoiseError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

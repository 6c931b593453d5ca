//! Denoising with Intel Open Image Denoise (OIDN 2), loaded at run time, never linked: the
//! library comes from an installed `pyoidn` wheel (which ships it), from `OIDN_DIR`, or
//! from the system's library path. Its "RT" filter takes the noisy colour with the albedo
//! and normal AOVs as guides (`crate::aov`), in high dynamic range.

use std::ffi::{c_char, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use libloading::Library;

/// The library's file name on this platform.
#[cfg(target_os = "linux")]
const LIB_NAMES: [&str; 2] = ["libOpenImageDenoise.so.2", "libOpenImageDenoise.so"];
#[cfg(target_os = "macos")]
const LIB_NAMES: [&str; 2] = ["libOpenImageDenoise.2.dylib", "libOpenImageDenoise.dylib"];
#[cfg(target_os = "windows")]
const LIB_NAMES: [&str; 2] = ["OpenImageDenoise.dll", "OpenImageDenoise.dll"];
#[cfg(not(any(target_os = "linux", target_os = "macos", target_os = "windows")))]
const LIB_NAMES: [&str; 2] = ["libOpenImageDenoise.so.2", "libOpenImageDenoise.so"];

/// What the denoiser refuses or meets.
#[derive(Debug, Clone, thiserror::Error)]
pub enum DenoiseError {
    #[error(
        "--denoise needs Intel Open Image Denoise 2, which was not found: install it with \
         `pip install pyoidn` (its wheel ships libOpenImageDenoise), or set OIDN_DIR to an \
         OIDN 2 release (the folder holding lib/{}); looked in: {}",
        LIB_NAMES[0],
        .searched.join(", ")
    )]
    NotFound { searched: Vec<String> },
    #[error("{}: not a usable Open Image Denoise 2 library: {reason}", path.display())]
    Unusable { path: PathBuf, reason: String },
    #[error("Open Image Denoise failed: {0}")]
    Failed(String),
}

// The C API's handles and enums (OpenImageDenoise/oidn.h, version 2).
type Handle = *mut c_void;
const DEVICE_TYPE_DEFAULT: i32 = 0;
const FORMAT_FLOAT3: i32 = 3;
const ERROR_NONE: i32 = 0;

/// The entry points wgtrace calls, resolved once.
struct Api {
    new_device: unsafe extern "C" fn(i32) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> i32,
    new_buffer: unsafe extern "C" fn(Handle, usize) -> Handle,
    write_buffer: unsafe extern "C" fn(Handle, usize, usize, *const c_void),
    read_buffer: unsafe extern "C" fn(Handle, usize, usize, *mut c_void),
    release_buffer: unsafe extern "C" fn(Handle),
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    set_image:
        unsafe extern "C" fn(Handle, *const c_char, Handle, i32, usize, usize, usize, usize, usize),
    set_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// A loaded Open Image Denoise.
pub struct Denoiser {
    api: Api,
    path: PathBuf,
    /// The device, committed on first use and kept (a CUDA device's start costs seconds);
    /// one filter runs on it at a time.
    device: Mutex<Option<Device>>,
    // keeps the entry points valid
    _lib: Library,
}

/// An OIDN device handle; OIDN's devices may be used from any thread, one call at a time
/// (the mutex around it).
struct Device(Handle);
// SAFETY: see above
unsafe impl Send for Device {}

/// The places searched, in order: `OIDN_DIR` (its `lib/` and itself), an installed
/// `pyoidn` (found by the `python3` on the path, or passed by the Python module), then the
/// system's library path by name.
fn candidates(pyoidn: Option<&Path>) -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) {
        let dir = PathBuf::from(dir);
        dirs.push(dir.join("lib"));
        dirs.push(dir.join("lib64"));
        dirs.push(dir);
    }
    match pyoidn {
        Some(p) => dirs.push(p.join("oidn").join("lib")),
        None => dirs.extend(pyoidn_dir().map(|p| p.join("oidn").join("lib"))),
    }
    let mut out: Vec<PathBuf> = dirs
        .iter()
        .flat_map(|d| LIB_NAMES.iter().map(move |n| d.join(n)))
        .collect();
    // bare names: the dynamic loader's own search (LD_LIBRARY_PATH, ldconfig's cache)
    out.extend(LIB_NAMES.iter().map(PathBuf::from));
    out
}

/// The folder of the `pyoidn` package the `python3` on the path would import, if any
/// (asked without importing it).
fn pyoidn_dir() -> Option<PathBuf> {
    let script = "import importlib.util as u\ns = u.find_spec('pyoidn')\n\
                  print(s.submodule_search_locations[0] if s else '')";
    let out = std::process::Command::new("python3")
        .args(["-c", script])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let dir = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!dir.is_empty()).then(|| PathBuf::from(dir))
}

impl Denoiser {
    /// The process's denoiser, loaded on first use.
    pub fn shared() -> Result<&'static Denoiser, DenoiseError> {
        Self::shared_with(None)
    }

    /// As [`Denoiser::shared`], with the folder of an installed `pyoidn` package known
    /// (the Python module asks its own interpreter).
    pub fn shared_with(pyoidn: Option<&Path>) -> Result<&'static Denoiser, DenoiseError> {
        static SHARED: OnceLock<Result<Denoiser, DenoiseError>> = OnceLock::new();
        SHARED
            .get_or_init(|| Self::load(pyoidn))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Loads the first library found (see [`candidates`]).
    pub fn load(pyoidn: Option<&Path>) -> Result<Denoiser, DenoiseError> {
        let list = candidates(pyoidn);
        for path in &list {
            if path.is_absolute() && !path.exists() {
                continue;
            }
            // SAFETY: loading runs the library's initialisers; OIDN's are its own
            // registration of device types
            let Ok(lib) = (unsafe { Library::new(path) }) else {
                continue;
            };
            return Self::from_library(lib, path.clone());
        }
        Err(DenoiseError::NotFound {
            searched: list.iter().map(|p| p.display().to_string()).collect(),
        })
    }

    fn from_library(lib: Library, path: PathBuf) -> Result<Denoiser, DenoiseError> {
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the signature is the one oidn.h (version 2) declares
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }.map_err(|e| {
                    DenoiseError::Unusable {
                        path: path.clone(),
                        reason: format!("no {} ({e})", $name),
                    }
                })?
            };
        }
        let api = Api {
            new_device: sym!("oidnNewDevice"),
            commit_device: sym!("oidnCommitDevice"),
            release_device: sym!("oidnReleaseDevice"),
            device_error: sym!("oidnGetDeviceError"),
            new_buffer: sym!("oidnNewBuffer"),
            write_buffer: sym!("oidnWriteBuffer"),
            read_buffer: sym!("oidnReadBuffer"),
            release_buffer: sym!("oidnReleaseBuffer"),
            new_filter: sym!("oidnNewFilter"),
            set_image: sym!("oidnSetFilterImage"),
            set_bool: sym!("oidnSetFilterBool"),
            commit_filter: sym!("oidnCommitFilter"),
            execute_filter: sym!("oidnExecuteFilter"),
            release_filter: sym!("oidnReleaseFilter"),
        };
        Ok(Denoiser {
            api,
            path,
            device: Mutex::new(None),
            _lib: lib,
        })
    }

    /// The library file loaded.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Denoises `color` (`width * height * 3` linear floats, row-major), guided by the
    /// albedo (clamped to [0, 1]) and normal AOVs when given (the normal only with the
    /// albedo, as OIDN requires).
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[f32],
        albedo: Option<&[f32]>,
        normal: Option<&[f32]>,
    ) -> Result<Vec<f32>, DenoiseError> {
        let n = width as usize * height as usize * 3;
        let sized = |v: &[f32]| v.len() == n;
        if !sized(color) || !albedo.is_none_or(sized) || !normal.is_none_or(sized) {
            return Err(DenoiseError::Failed("image sizes differ".into()));
        }
        let albedo: Option<Vec<f32>> =
            albedo.map(|a| a.iter().map(|x| x.clamp(0.0, 1.0)).collect());
        let normal = normal.filter(|_| albedo.is_some());
        let api = &self.api;
        let bytes = n * 4;
        let mut kept = self.device.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: the device is created once and kept; every other handle is created here
        // and released before returning; buffers are `bytes` long and read or written
        // within that
        unsafe {
            let device = match kept.as_ref() {
                Some(d) => d.0,
                None => {
                    let d = (api.new_device)(DEVICE_TYPE_DEFAULT);
                    if d.is_null() {
                        return Err(DenoiseError::Failed("no device".into()));
                    }
                    (api.commit_device)(d);
                    d
                }
            };
            let check = || -> Result<(), DenoiseError> {
                let mut msg: *const c_char = std::ptr::null();
                if (api.device_error)(device, &mut msg) == ERROR_NONE {
                    return Ok(());
                }
                let text = if msg.is_null() {
                    "unknown error".into()
                } else {
                    CStr::from_ptr(msg).to_string_lossy().into_owned()
                };
                Err(DenoiseError::Failed(text))
            };
            // a device that failed to commit is released, and the next call tries anew
            if let Err(e) = check() {
                if kept.is_none() {
                    (api.release_device)(device);
                }
                return Err(e);
            }
            *kept = Some(Device(device));
            (|| {
                let filter = (api.new_filter)(device, c"RT".as_ptr());
                check()?;
                let mut buffers = Vec::new();
                let mut image = |name: &str, data: Option<&[f32]>| {
                    let buf = (api.new_buffer)(device, bytes);
                    if let Some(d) = data {
                        (api.write_buffer)(buf, 0, bytes, d.as_ptr().cast());
                    }
                    let name = CString::new(name).expect("no NUL");
                    (api.set_image)(
                        filter,
                        name.as_ptr(),
                        buf,
                        FORMAT_FLOAT3,
                        width as usize,
                        height as usize,
                        0,
                        0,
                        0,
                    );
                    buffers.push(buf);
                    buf
                };
                image("color", Some(color));
                if let Some(a) = &albedo {
                    image("albedo", Some(a));
                }
                if let Some(nrm) = normal {
                    image("normal", Some(nrm));
                }
                let output = image("output", None);
                (api.set_bool)(filter, c"hdr".as_ptr(), true);
                (api.commit_filter)(filter);
                let run = check().and_then(|_| {
                    (api.execute_filter)(filter);
                    check()
                });
                let mut out = vec![0.0f32; n];
                if run.is_ok() {
                    (api.read_buffer)(output, 0, bytes, out.as_mut_ptr().cast());
                }
                for b in buffers {
                    (api.release_buffer)(b);
                }
                (api.release_filter)(filter);
                run.and(check()).map(|_| out)
            })()
        }
    }
}

//! What can stop a convergence study.

use std::path::{Path, PathBuf};

use crate::gpu::error::GpuError;
use crate::scene::error::SceneError;
use crate::session::SessionError;

#[derive(Debug, thiserror::Error)]
pub enum ConvergeError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
    #[error(transparent)]
    Denoise(#[from] crate::denoise::DenoiseError),
    #[error("{}: {message}", path.display())]
    File { path: PathBuf, message: String },
    #[error("{0}")]
    Invalid(String),
}

pub(super) fn file_err(path: &Path, e: impl std::fmt::Display) -> ConvergeError {
    ConvergeError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

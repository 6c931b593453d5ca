//! The error of a glTF file: the JSON path of what is at fault and what is wrong with it.

/// A problem in a glTF file: the JSON path of what is at fault (e.g.
/// `meshes[3].primitives[0].attributes.POSITION`) and what is wrong with it.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfError {
    pub key: String,
    pub message: String,
}

impl GltfError {
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        GltfError {
            key: key.into(),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for GltfError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.key, self.message)
        }
    }
}

/// A result whose error is a [`GltfError`].
pub type Result<T> = std::result::Result<T, GltfError>;

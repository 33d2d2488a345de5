//! What can go wrong when building or tracing W^n(A), in a file of its own so that every part
//! of the ray tracer can name it without importing the module that drives them.

#[derive(Debug, thiserror::Error)]
pub enum RaytraceError {
    #[error("the scene has no enabled function")]
    NoFunctions,
    #[error("the scene has {0} enabled functions; the ray tracer handles at most 16")]
    TooManyFunctions(usize),
    #[error("enabled function {0} has no Lipschitz bound (Julia maps cannot be ray traced)")]
    NoLipschitzBound(usize),
    #[error("{path}: not a usable glTF mesh: {message}")]
    Gltf { path: String, message: String },
    #[error("too large: {0}")]
    TooLarge(String),
    #[error("cancelled")]
    Cancelled,
}

impl RaytraceError {
    /// Whether the user's input caused it (exit code 2 on the command line).
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, RaytraceError::Cancelled)
    }
}

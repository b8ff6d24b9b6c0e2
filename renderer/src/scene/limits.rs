//! How much a scene file may ask for: each size a file declares is checked against these
//! before anything of that size is allocated, so that a small hostile file (a 600 KB PNG can
//! declare 20000 x 20000 texels, a few nodes can instance a mesh a million times) is refused
//! with a message instead of taking the machine's memory. The defaults admit every model in
//! common use; each has a command-line flag to raise it.

/// Sizes a scene file may declare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadLimits {
    /// Texels one image may declare (decoded to 4 bytes each).
    pub max_texels: u64,
    /// Bytes of all buffers together.
    pub max_buffer_bytes: u64,
    /// Triangles in the scene, each instance of a mesh counted.
    pub max_triangles: u64,
    /// Levels of the node hierarchy (walked recursively: at most `MAX_NODE_DEPTH`).
    pub max_node_depth: u64,
}

/// 8192 x 8192, the largest texture in common use (256 MiB as RGBA8).
pub const DEFAULT_MAX_TEXELS: u64 = 8192 * 8192;
/// 4 GiB: more than the largest glTF files published (a few hundred MB).
pub const DEFAULT_MAX_BUFFER_BYTES: u64 = 4 << 30;
/// 50 million triangles, about 10 GB once the BVH is built (`caustica info` prints the
/// memory a scene takes).
pub const DEFAULT_MAX_TRIANGLES: u64 = 50_000_000;

/// 256 levels: deeper than any modelling tool nests.
pub const DEFAULT_MAX_NODE_DEPTH: u64 = 256;
/// The deepest walk the loader's stack allows (a loading thread has 2 MiB).
pub const MAX_NODE_DEPTH: u64 = 1024;

impl Default for LoadLimits {
    fn default() -> Self {
        LoadLimits {
            max_texels: DEFAULT_MAX_TEXELS,
            max_buffer_bytes: DEFAULT_MAX_BUFFER_BYTES,
            max_triangles: DEFAULT_MAX_TRIANGLES,
            max_node_depth: DEFAULT_MAX_NODE_DEPTH,
        }
    }
}

impl LoadLimits {
    /// The message for a file that asks for `what` where `limit` allows, raised by `flag`.
    pub fn refusal(what: &str, limit: u64, flag: &str) -> String {
        format!("{what}, over the limit of {limit} (raise it with {flag})")
    }
}

//! File formats, in one place: OpenEXR ([`exr`]) and PNG ([`png`]) images, NumPy `.npy` grids
//! ([`npy`]), PLY and OBJ triangle meshes ([`mesh`]; read also from STL and OFF: [`mesh_read`]), JSON read strictly (`json`: the base of the
//! scene and `OPT.json` readers), and output files written whole or not at all ([`files`]).
//!
//! Rendering types never see a file: the scene reader, the film and the grids call these at the edge.

pub mod exr;
pub mod files;
pub(crate) mod json;
pub mod mesh;
pub mod mesh_read;
pub mod npy;
pub mod png;

pub use exr::{Channels, read_exr, read_exr_rgb, rgb_from_channels, write_exr};
pub use files::{
    Writer, bytes_writer, check_output_folder, check_output_path, create_parent, file_message,
    file_name, write_all_or_nothing, write_exr_and_png,
};
pub use mesh::{MESH_EXTENSIONS, ply_bytes, write_mesh};
pub use mesh_read::{MESH_READ_EXTENSIONS, read_mesh};
pub use npy::{NpyArray, read_npy, read_npy_array, write_npy, write_npy_array};
pub use png::{srgb_encode, write_png};

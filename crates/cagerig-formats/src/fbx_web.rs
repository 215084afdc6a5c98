//! FBX on the web target: not available. FBX is read through ufbx, a C library, and the web
//! edition is built without a C compiler for wasm; each function names the file and says what to
//! do instead (convert it to glTF, or open it in the native studio).

use std::path::Path;

use crate::{FormatError, ImportOptions, ImportedCharacter, StaticMesh};

/// Why the web edition cannot read `path`.
fn unavailable(path: &Path) -> FormatError {
    FormatError::Fbx {
        path: path.to_path_buf(),
        message: "FBX files are not read in the web edition (the FBX reader is a C library that \
                  is not built for the browser); export the character as glTF (.glb) or open it \
                  in the native studio"
            .into(),
    }
}

/// Always an error on the web target: see the [module documentation](self).
pub fn import_fbx(path: &Path, _options: &ImportOptions) -> Result<ImportedCharacter, FormatError> {
    Err(unavailable(path))
}

/// Always an error on the web target: see the [module documentation](self).
pub fn import_fbx_bytes(
    _bytes: &[u8],
    path: &Path,
    _options: &ImportOptions,
) -> Result<ImportedCharacter, FormatError> {
    Err(unavailable(path))
}

/// Always an error on the web target: see the [module documentation](self).
pub fn import_fbx_static(path: &Path) -> Result<StaticMesh, FormatError> {
    Err(unavailable(path))
}

/// Always an error on the web target: see the [module documentation](self).
pub fn import_fbx_static_bytes(_bytes: &[u8], path: &Path) -> Result<StaticMesh, FormatError> {
    Err(unavailable(path))
}

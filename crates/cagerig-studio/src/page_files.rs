//! The files of the web edition. A web page has no file system for the studio to browse, so
//! there characters are chosen through the page's file input, samples are fetched by the page,
//! and a saved session or an exported `.glb` is handed to the page as a download. The page
//! implements [`PageFiles`] and passes it in [`crate::StartupOptions::page_files`]; the native
//! studio has none and uses its own dialogs.

use std::sync::Arc;

/// What the page does with files for the studio (see the [module documentation](self)).
pub trait PageFiles: std::fmt::Debug {
    /// Opens the page's file chooser for a character (`.glb`, `.gltf`). The page hands the chosen
    /// file's bytes back with [`crate::StudioApp::open_character_bytes`].
    fn choose_character(&self);
    /// The samples the page serves beside itself (file names, such as `Fox.glb`), for the File
    /// menu.
    fn samples(&self) -> Vec<String>;
    /// Fetches sample `name` (one of [`Self::samples`]); its bytes come back as a chosen file's.
    fn fetch_sample(&self, name: &str);
    /// Reads a file dropped on the studio (the browser reads it asynchronously) and opens it as
    /// a chosen file.
    fn open_dropped(&self, file: egui::DroppedFileHandle);
    /// Offers `bytes` as a download named `file_name` of MIME type `mime`.
    fn download(&self, file_name: &str, mime: &str, bytes: &[u8]) -> Result<(), String>;
}

/// The page's files, shared by the parts of the studio that open and save.
pub type SharedPageFiles = Arc<dyn PageFiles>;

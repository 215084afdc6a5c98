//! cagerig studio in the browser: the same studio (`cagerig-studio`, over `cagerig`,
//! `cagerig-document`, `cagerig-render` and the glTF half of `cagerig-formats`) built for
//! `wasm32-unknown-unknown`, with what only a web page has:
//!
//! | module | concern |
//! |---|---|
//! | `rig_state` | the rig's state as the page's test hook reports it (S', C, C', M'), on every target |
//! | `page` (web only) | the page's files (file input, samples, downloads) and the exports the page calls |
//!
//! `web/build.sh` builds it and writes the static site to `target/web/`; `docs/web.md` tells
//! how it is built, served and tested.

pub mod rig_state;

#[cfg(target_arch = "wasm32")]
mod page;

// The page's worker: the slow part of opening a character, off the page's thread. It runs its own
// instance of the studio's module (cagerig_web.js) and answers each {id, name, bytes} with the
// cage that opening the file generates ({id, cage}: JSON, or null when the file has its cage) or
// with why the file cannot be opened ({id, error}). The page then opens the file with that cage
// (crates/cagerig-web/src/page.rs: generated_cage, open_file).
import init, { generated_cage } from "./cagerig_web.js";

const ready = init();

self.onmessage = async (event) => {
  const { id, name, bytes } = event.data;
  const started = performance.now();
  try {
    await ready;
    const cage = generated_cage(name, new Uint8Array(bytes));
    self.postMessage({ id, cage: cage ?? null, ms: performance.now() - started });
  } catch (e) {
    self.postMessage({ id, error: String(e), ms: performance.now() - started });
  }
};

// The page's worker: the slow parts of opening a character and of binding, off the page's
// thread. It runs its own instance of the studio's module (cagerig_web.js) and answers
//   {id, name, bytes}        with the cage that opening the file generates ({id, cage}: JSON, or
//                            null when the file has its cage) or why the file cannot be opened
//                            ({id, error}); the page then opens the file with that cage;
//   {kind: "weights", id, input}  (a Bind's automatic weights, JSON) with {kind: "weights", id,
//                            progress: {stage, done, total}} messages as they are computed, then
//                            {kind: "weights", id, output} (JSON) or {kind: "weights", id, error};
//                            the page then binds the rig with them.
// (crates/cagerig-web/src/page.rs: generated_cage, open_file; automatic_weights,
// weights_progress, weights_finished.)
import init, { automatic_weights, generated_cage } from "./cagerig_web.js";

const ready = init();
let weightsId = null;  // the id of the automatic weights being computed

// Called by the module while it computes automatic weights.
self.cagerigWorker = {
  weightsProgress(stage, done, total) {
    self.postMessage({ kind: "weights", id: weightsId, progress: { stage, done, total } });
  },
};

self.onmessage = async (event) => {
  const { kind, id } = event.data;
  const started = performance.now();
  const reply = (answer) => self.postMessage({ ...answer, id, ms: performance.now() - started });
  if (kind === "weights") {
    try {
      await ready;
      weightsId = id;
      reply({ kind, output: automatic_weights(event.data.input) });
    } catch (e) {
      reply({ kind, error: String(e) });
    } finally {
      weightsId = null;
    }
    return;
  }
  try {
    await ready;
    const cage = generated_cage(event.data.name, new Uint8Array(event.data.bytes));
    reply({ cage: cage ?? null });
  } catch (e) {
    reply({ error: String(e) });
  }
};

// Whether a Worker is still alive. A Worker the browser ends (out of memory, a crash)
// or that closes itself sends no message and fires no event on its owner: its
// requests would wait for ever. Each of the page's Workers therefore holds a Web Lock
// named in its URL (`?life=NAME`) from its start to its end; its owner, once it sees
// the lock held, asks for the same lock, which the browser grants only once the
// Worker is gone. (Not a message from the Worker saying it holds it: a message posted
// just before a Worker ends can be lost with it.)
//
//   owner:  const name = lifelineName('kind'); new Worker(withLifeline(url, name), …);
//           const stop = watchLifeline(name, onDeath); … before terminating it on purpose: stop();
//   Worker: holdLifeline();
// Without the Web Locks API (an insecure context) nothing is watched.

let count = 0;

// A lock name of this page's own.
export function lifelineName(kind) {
  const id = globalThis.crypto?.randomUUID?.() ?? `${Date.now()}-${Math.random()}`;
  return `localisebot-${kind}-${id}-${count++}`;
}

// `url` (a URL) with the lock's name in its query.
export function withLifeline(url, name) {
  const u = new URL(url);
  u.searchParams.set('life', name);
  return u;
}

// In a Worker: takes the lock named in its URL and keeps it until the Worker ends;
// resolves once it is held (at once when there is none to hold).
export function holdLifeline() {
  const name = new URL(self.location.href).searchParams.get('life');
  if (!name || !navigator.locks) return Promise.resolve();
  return new Promise((held) => {
    navigator.locks.request(name, () => {
      held();
      return new Promise(() => {}); // never released: the Worker's end releases it
    });
  });
}

// In the owner: `onDeath()` once the Worker holding `name` has ended — from when it is
// seen holding it (polled, every 50 ms to 1 s). Returns a function that stops watching
// (call it before terminating the Worker on purpose).
export function watchLifeline(name, onDeath) {
  if (!navigator.locks) return () => {};
  const stop = new AbortController();
  (async () => {
    for (let wait = 50; !stop.signal.aborted; wait = Math.min(2 * wait, 1000)) {
      const { held } = await navigator.locks.query();
      if (held.some((l) => l.name === name)) break;
      await new Promise((ok) => setTimeout(ok, wait));
    }
    await navigator.locks.request(name, { signal: stop.signal }, () => {
      if (!stop.signal.aborted) onDeath();
    });
  })().catch(() => {}); // aborted
  return () => stop.abort();
}

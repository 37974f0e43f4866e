// Turns a set of dropped or chosen files into one scene: a scene.json, or one
// camera JSON per view plus masks (and images), plus the mesh. Plain functions,
// used by the worker; the file lookup by path (full path, path suffix, then file
// name) is done by the wasm FileSet.
//
// A file is { path, bytes: Uint8Array }, path being its folder-relative path when
// the browser gives one (a dropped folder) and its bare name otherwise.

const MESH = /\.(glb|gltf|obj)$/i;
const PNG = /\.png$/i;
const JSON_FILE = /\.json$/i;

export const baseName = (p) => p.split(/[\\/]/).pop();
const stem = (p) => baseName(p).replace(/\.[^.]*$/, '');

// Parses a JSON file, with an error naming it.
function parseJson(file) {
  const text = new TextDecoder().decode(file.bytes);
  try {
    return { text, value: JSON.parse(text) };
  } catch (e) {
    throw new Error(`${file.path}: not valid JSON (${e.message})`);
  }
}

// Sorts the files into meshes, PNGs, scene files and camera files.
export function classify(files) {
  const out = { meshes: [], pngs: [], scenes: [], cameras: [], ignored: [] };
  for (const f of files) {
    if (MESH.test(f.path)) out.meshes.push(f);
    else if (PNG.test(f.path)) out.pngs.push(f);
    else if (JSON_FILE.test(f.path)) {
      const { text, value } = parseJson(f);
      if (value && typeof value.mesh === 'string' && Array.isArray(value.views)) out.scenes.push({ file: f, text, value });
      else if (value && (value.camera || 'fx' in value)) out.cameras.push({ file: f, value });
      else out.ignored.push(f.path);
    } else out.ignored.push(f.path);
  }
  return out;
}

// The mask and image of a view named `name` among the PNGs, by naming habit:
// masks/NAME.png, NAME_mask.png, NAME.mask.png, mask_NAME.png for the mask;
// images/NAME.png, NAME_image.png, NAME_rgb.png for the image; a lone NAME.png is
// the mask, and two files named NAME.png are told apart by their content (in wasm).
function matchView(name, pngs) {
  const n = name.replace(/[.*+?^${}()|[\]\\]/g, '\\$&');
  const find = (res) => pngs.find((f) => res.some((re) => re.test(f.path)))?.path;
  const mask = find([
    new RegExp(`(^|/)masks?/${n}\\.png$`, 'i'),
    new RegExp(`(^|/)${n}[._-]mask\\.png$`, 'i'),
    new RegExp(`(^|/)mask[._-]${n}\\.png$`, 'i'),
  ]);
  const image = find([
    new RegExp(`(^|/)(images?|rgb)/${n}\\.png$`, 'i'),
    new RegExp(`(^|/)${n}[._-](image|rgb|color|colour)\\.png$`, 'i'),
  ]);
  const plain = pngs.filter((f) => baseName(f.path).toLowerCase() === `${name.toLowerCase()}.png`);
  if (mask) return { mask, image: image ?? (plain.length === 1 && plain[0].path !== mask ? plain[0].path : undefined) };
  if (plain.length === 0) return {};
  if (image) return { mask: plain.find((f) => f.path !== image)?.path, image };
  return plain.length === 1 ? { mask: plain[0].path } : { mask: `${name}.png`, image: `${name}.png` };
}

// A scene from per-view camera files: each NAME.json (a camera, or a scene view
// entry with "camera" and optionally "mask"/"image") becomes a view named NAME.
function sceneFromCameras(cameras, meshes, pngs) {
  if (meshes.length !== 1) {
    throw new Error(
      meshes.length === 0
        ? 'no mesh: add a .glb, .gltf (with its .bin) or .obj file'
        : `several meshes (${meshes.map((m) => m.path).join(', ')}): choose one`,
    );
  }
  const views = cameras.map(({ file, value }) => {
    const name = value.name ?? stem(file.path);
    const found = matchView(name, pngs);
    const mask = value.mask ?? found.mask;
    if (!mask) throw new Error(`view '${name}' (${file.path}): no mask: add ${name}.png or masks/${name}.png`);
    const view = { name, mask, camera: value.camera ?? value };
    const image = value.image ?? found.image;
    if (image) view.image = image;
    return view;
  });
  views.sort((a, b) => a.name.localeCompare(b.name, undefined, { numeric: true }));
  return { version: 1, mesh: meshes[0].path, views };
}

// The plan for a file set: { sceneFile, sceneText } to hand to Session.fromScene, or
// { meshOnly } when a mesh came without a scene (the caller checks it, then reports
// what is missing). Throws an Error with a specific message otherwise.
export function planScene(files) {
  if (files.length === 0) throw new Error('no files were given');
  const { meshes, pngs, scenes, cameras } = classify(files);
  if (scenes.length > 1) {
    throw new Error(`several scene files (${scenes.map((s) => s.file.path).join(', ')}): give one scene at a time`);
  }
  if (scenes.length === 1) {
    const { file, text, value } = scenes[0];
    // A mesh dropped under another name than the scene's: use it when it is the only one.
    const wanted = typeof value.mesh === 'string' ? baseName(value.mesh).toLowerCase() : null;
    if (wanted && meshes.length === 1 && !files.some((f) => baseName(f.path).toLowerCase() === wanted)) {
      value.mesh = meshes[0].path;
      return { sceneFile: file.path, sceneText: JSON.stringify(value) };
    }
    return { sceneFile: file.path, sceneText: text };
  }
  if (cameras.length > 0) {
    const scene = sceneFromCameras(cameras, meshes, pngs);
    return { sceneFile: 'cameras.json', sceneText: JSON.stringify(scene) };
  }
  if (meshes.length > 0) return { meshOnly: meshes[0] };
  throw new Error(
    `no scene.json or camera .json among ${files.map((f) => f.path).join(', ')}: ` +
      'give a scene.json (or one camera .json per view) with the mesh, masks and images',
  );
}

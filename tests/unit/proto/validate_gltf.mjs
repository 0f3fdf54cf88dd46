// validate_gltf.mjs — test helper: validates a .glb with the Khronos glTF validator and
// decodes every KHR_draco_mesh_compression primitive with draco3d (Draco's own JavaScript
// decoder, the family the browser uses), looking attributes up by the unique ids the glTF
// names. Prints one JSON report on stdout:
//   {"errors", "warnings", "infos", "messages": [{"code", "severity", "message", "pointer"}],
//    "draco": [{"mesh", "points", "faces", "accessors_match", "attributes":
//               {NAME: {"unique_id", "found", "components", "min", "max"}}}]}
// Usage: node validate_gltf.mjs FILE.glb
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import validator from 'gltf-validator';

const require = createRequire(import.meta.url);
const draco3d = require('draco3d');

const TYPE_SIZE = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };

function chunks(bytes) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const jsonLen = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLen)));
  let bin = null;
  if (20 + jsonLen < bytes.length) {
    const binLen = dv.getUint32(20 + jsonLen, true);
    bin = bytes.subarray(28 + jsonLen, 28 + jsonLen + binLen);
  }
  return { json, bin };
}

async function decodeDraco(json, bin) {
  const out = [];
  const meshes = json.meshes || [];
  if (!meshes.some((m) => m.primitives.some((p) => p.extensions?.KHR_draco_mesh_compression)))
    return out;
  const dm = await draco3d.createDecoderModule({});
  meshes.forEach((mesh, mi) => {
    for (const prim of mesh.primitives) {
      const ext = prim.extensions?.KHR_draco_mesh_compression;
      if (!ext) continue;
      const view = json.bufferViews[ext.bufferView];
      const data = bin.subarray(view.byteOffset || 0, (view.byteOffset || 0) + view.byteLength);
      const decoder = new dm.Decoder();
      const buffer = new dm.DecoderBuffer();
      buffer.Init(new Int8Array(data.buffer, data.byteOffset, data.byteLength), data.byteLength);
      const geom = new dm.Mesh();
      const status = decoder.DecodeBufferToMesh(buffer, geom);
      const rec = { mesh: mi, ok: status.ok(), points: geom.num_points(), faces: geom.num_faces(),
                    attributes: {}, accessors_match: true };
      for (const [name, uid] of Object.entries(ext.attributes)) {
        const acc = json.accessors[prim.attributes[name]];
        const att = decoder.GetAttributeByUniqueId(geom, uid);
        const found = att && att.ptr !== 0;
        const a = { unique_id: uid, found, components: found ? att.num_components() : 0 };
        if (found) {
          const values = new dm.DracoFloat32Array();
          decoder.GetAttributeFloatForAllPoints(geom, att, values);
          let min = Infinity, max = -Infinity;
          for (let i = 0; i < values.size(); i++) {
            min = Math.min(min, values.GetValue(i));
            max = Math.max(max, values.GetValue(i));
          }
          dm.destroy(values);
          a.min = min;
          a.max = max;
        }
        if (!acc || acc.count !== rec.points || !found || TYPE_SIZE[acc.type] !== a.components)
          rec.accessors_match = false;
        rec.attributes[name] = a;
      }
      const idx = json.accessors[prim.indices];
      if (!idx || idx.count !== 3 * rec.faces) rec.accessors_match = false;
      out.push(rec);
      dm.destroy(geom);
      dm.destroy(buffer);
      dm.destroy(decoder);
    }
  });
  return out;
}

const bytes = new Uint8Array(readFileSync(process.argv[2]));
const report = await validator.validateBytes(bytes, { maxIssues: 100, writeTimestamp: false });
const { json, bin } = chunks(bytes);
const result = {
  errors: report.issues.numErrors,
  warnings: report.issues.numWarnings,
  infos: report.issues.numInfos,
  messages: report.issues.messages.map((m) => ({ code: m.code, severity: m.severity,
                                                 message: m.message, pointer: m.pointer })),
  draco: await decodeDraco(json, bin),
};
process.stdout.write(JSON.stringify(result) + '\n');

// draco.mjs — decodes a .drc file in Node with npm draco3d (a decoder build independent of the
// one the viewer uses) and reads isomesh's attributes by their fixed unique ids, each checked
// against its metadata name (proto/draco_encode.h).
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const draco3d = require('draco3d');

let decoderModule = null;

async function module() {
  if (!decoderModule) decoderModule = await draco3d.createDecoderModule({});
  return decoderModule;
}

export const ATTRIBUTE_IDS = { position: 0, normal: 1, mean_curvature: 2, gauss_curvature: 3, class: 4 };
// Triangle labels, present only when the surface has them (curves asked for, double sheets).
export const LABEL_IDS = { cell: 5, double_sheet: 6 };

// The integer attributes and how draco3d reads them; the rest are float32.
const INTEGER_READERS = {
  class: ['DracoUInt8Array', 'GetAttributeUInt8ForAllPoints', Uint8Array],
  double_sheet: ['DracoUInt8Array', 'GetAttributeUInt8ForAllPoints', Uint8Array],
  cell: ['DracoUInt32Array', 'GetAttributeUInt32ForAllPoints', Uint32Array],
};

// Returns {points, faces, index: Uint32Array, attributes: {name: {uniqueId, components, values}}}.
export async function decodeDraco(bytes) {
  const draco = await module();
  const decoder = new draco.Decoder();
  const mesh = new draco.Mesh();
  try {
    const array = new Int8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const status = decoder.DecodeArrayToMesh(array, array.byteLength, mesh);
    if (!status.ok()) throw new Error('draco3d: ' + status.error_msg());
    const out = { points: mesh.num_points(), faces: mesh.num_faces(), attributes: {} };
    for (const [name, id] of Object.entries({ ...ATTRIBUTE_IDS, ...LABEL_IDS })) {
      const index = decoder.GetAttributeIdByMetadataEntry(mesh, 'name', name);
      if (index < 0) continue;
      const attr = decoder.GetAttribute(mesh, index);
      const n = out.points * attr.num_components();
      const [arrayType, read, Typed] = INTEGER_READERS[name] || ['DracoFloat32Array', 'GetAttributeFloatForAllPoints', Float32Array];
      const arr = new draco[arrayType]();
      decoder[read](mesh, attr, arr);
      const values = new Typed(n);
      for (let i = 0; i < n; i++) values[i] = arr.GetValue(i);
      draco.destroy(arr);
      out.attributes[name] = { uniqueId: attr.unique_id(), components: attr.num_components(),
        type: attr.attribute_type(), values, expectedId: id };
    }
    const faces = new draco.DracoInt32Array();
    out.index = new Uint32Array(out.faces * 3);
    for (let f = 0; f < out.faces; f++) {
      decoder.GetFaceFromMesh(mesh, f, faces);
      for (let k = 0; k < 3; k++) out.index[3 * f + k] = faces.GetValue(k);
    }
    draco.destroy(faces);
    return out;
  } finally {
    draco.destroy(mesh);
    draco.destroy(decoder);
  }
}

// draco_worker.js — decodes isomesh's Draco meshes off the main thread with the decoder module's
// own API (three's DRACOLoader reads position/normal/color/uv only, and at most one generic
// attribute through defaultAttributeIDs). The decoder is the one shipped inside three
// (examples/jsm/libs/draco), served by isomeshd under /vendor/three/.
//
// Attributes are looked up by the protocol's fixed unique ids (proto/draco_encode.h). A wrong
// id would fail silently — you would paint Gaussian curvature as mean curvature — so every
// attribute is checked three ways before it is used: the attribute found by its metadata
// "name" must be the one with the expected unique id, and its Draco type, component count
// must be the expected ones. Any mismatch is an error, never a quiet fallback.
/* global DracoDecoderModule, importScripts */
'use strict';

const DRACO_DIR = '/vendor/three/examples/jsm/libs/draco/';
importScripts(DRACO_DIR + 'draco_wasm_wrapper.js');

// The wire contract: unique id, metadata name, Draco attribute type, components, typed array.
const ATTRIBUTES = [
  { id: 0, name: 'position', type: 'POSITION', components: 3, array: 'Float32Array', required: true },
  { id: 1, name: 'normal', type: 'NORMAL', components: 3, array: 'Float32Array' },
  { id: 2, name: 'mean_curvature', type: 'GENERIC', components: 1, array: 'Float32Array' },
  { id: 3, name: 'gauss_curvature', type: 'GENERIC', components: 1, array: 'Float32Array' },
  { id: 4, name: 'class', type: 'GENERIC', components: 1, array: 'Uint8Array' },
  // Triangle labels (vertices split where they change, so a triangle's three points agree):
  { id: 5, name: 'cell', type: 'GENERIC', components: 1, array: 'Uint32Array' },
  { id: 6, name: 'double_sheet', type: 'GENERIC', components: 1, array: 'Uint8Array' },
];

let modulePromise = null;

function loadDecoder() {
  if (!modulePromise) {
    modulePromise = fetch(DRACO_DIR + 'draco_decoder.wasm')
      .then((r) => {
        if (!r.ok) throw new Error(`the Draco decoder could not be loaded (HTTP ${r.status})`);
        return r.arrayBuffer();
      })
      .then((wasmBinary) => new Promise((resolve) => {
        // The module object is thenable: hand it over wrapped, never as a promise's value.
        DracoDecoderModule({ wasmBinary, onModuleLoaded: (draco) => resolve({ draco }) });
      }));
  }
  return modulePromise;
}

function dracoDataType(draco, arrayName) {
  return { Uint8Array: draco.DT_UINT8, Uint32Array: draco.DT_UINT32 }[arrayName] ?? draco.DT_FLOAT32;
}

function readAttribute(draco, decoder, mesh, attr, spec) {
  const count = mesh.num_points();
  const Typed = self[spec.array];
  const n = count * spec.components;
  const bytes = n * Typed.BYTES_PER_ELEMENT;
  const ptr = draco._malloc(bytes);
  try {
    const ok = decoder.GetAttributeDataArrayForAllPoints(mesh, attr, dracoDataType(draco, spec.array), bytes, ptr);
    if (!ok) throw new Error(`could not read the Draco attribute '${spec.name}'`);
    return new Typed(draco.HEAPF32.buffer, ptr, n).slice(); // ptr is a byte offset
  } finally {
    draco._free(ptr);
  }
}

// Finds spec's attribute and proves it is the right one; null when the file does not carry it.
function findAttribute(draco, decoder, mesh, spec) {
  const byId = decoder.GetAttributeByUniqueId(mesh, spec.id);
  const index = decoder.GetAttributeIdByMetadataEntry(mesh, 'name', spec.name);
  const present = byId && byId.ptr !== 0;
  if (!present && index < 0) {
    if (spec.required) throw new Error(`the mesh has no '${spec.name}' attribute`);
    return null;
  }
  if (!present || index < 0) {
    throw new Error(`attribute '${spec.name}': unique id ${spec.id} and metadata name disagree ` +
      `(${present ? 'no metadata entry' : 'no attribute with that id'})`);
  }
  const byName = decoder.GetAttribute(mesh, index);
  if (byName.unique_id() !== spec.id) {
    throw new Error(`attribute '${spec.name}' has unique id ${byName.unique_id()}, expected ${spec.id}`);
  }
  if (byId.attribute_type() !== draco[spec.type]) {
    throw new Error(`attribute '${spec.name}' (id ${spec.id}) is not of Draco type ${spec.type}`);
  }
  if (byId.num_components() !== spec.components) {
    throw new Error(`attribute '${spec.name}' has ${byId.num_components()} components, expected ${spec.components}`);
  }
  return byId;
}

function decode(draco, bytes) {
  const decoder = new draco.Decoder();
  const mesh = new draco.Mesh();
  try {
    const array = new Int8Array(bytes);
    if (decoder.GetEncodedGeometryType(array) !== draco.TRIANGULAR_MESH) {
      throw new Error('the file is not a Draco triangle mesh');
    }
    const status = decoder.DecodeArrayToMesh(array, array.byteLength, mesh);
    if (!status.ok() || mesh.ptr === 0) throw new Error('Draco decoding failed: ' + status.error_msg());
    const out = { points: mesh.num_points(), faces: mesh.num_faces(), attributes: {} };
    for (const spec of ATTRIBUTES) {
      const attr = findAttribute(draco, decoder, mesh, spec);
      if (attr) out.attributes[spec.name] = readAttribute(draco, decoder, mesh, attr, spec);
    }
    const nIndex = out.faces * 3;
    const ptr = draco._malloc(nIndex * 4);
    try {
      decoder.GetTrianglesUInt32Array(mesh, nIndex * 4, ptr);
      out.index = new Uint32Array(draco.HEAPF32.buffer, ptr, nIndex).slice();
    } finally {
      draco._free(ptr);
    }
    return out;
  } finally {
    draco.destroy(mesh);
    draco.destroy(decoder);
  }
}

self.onmessage = async (event) => {
  const { id, bytes } = event.data;
  try {
    const { draco } = await loadDecoder();
    const result = decode(draco, bytes);
    const transfer = Object.values(result.attributes).map((a) => a.buffer);
    transfer.push(result.index.buffer);
    self.postMessage({ id, result }, transfer);
  } catch (e) {
    self.postMessage({ id, error: String(e && e.message ? e.message : e) });
  }
};

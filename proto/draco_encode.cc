// draco_encode.cc — builds a draco::Mesh directly from the indexed arrays (identity mapping
// from points to attribute values: no deduplication pass, which would cost 30-40 ms per 100k
// triangles for the same bytes) and encodes it with edgebreaker. The only C++ in isomesh;
// nothing escapes it but a C struct and a message.
//
// Encoding speed (ISM_DRACO_DEFAULT_SPEED = 4, for encoding and decoding), chosen by
// measurement with tests/bench/bench_wire on polygoniser meshes (torus, sphere, gyroid, Klein
// bottle; 14 position bits, 10 normal bits):
//   speeds 5-7   identical tools and sizes: positions 1.42-1.86 B/triangle;
//   speed 4      Draco's costlier tools for positions and connectivity: 6-11% smaller
//                (1.26-1.75 B/tri) at about the same encode rate (3-5 Mtri/s positions
//                only, 2.5-3 Mtri/s with normals);
//   speeds 0-3   normals another 6-8% smaller, but encoding with normals falls to
//                1.4-2.4 Mtri/s, under the service's goal of 2 Mtri/s;
//   speeds 8-10  weaker prediction, then the sequential coder (4-7x larger).
// So 4 is the smallest output that keeps encoding comfortably above 2 Mtri/s.
#include "proto/draco_encode.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>

#include "draco/compression/encode.h"
#include "draco/compression/expert_encode.h"
#include "draco/mesh/mesh.h"
#include "draco/metadata/geometry_metadata.h"

namespace {

void set_error(ism_draco_output *out, const char *what)
{
    std::snprintf(out->error, sizeof out->error, "draco: %s", what);
}

// Adds an attribute with the given values, its fixed unique id and a metadata entry "name".
// point_vertex NULL: one value per point (identity mapping); else point p takes value
// point_vertex[p] (nvalues values). Returns the attribute id inside the mesh, -1 on failure.
int add_attribute(draco::Mesh &mesh, draco::GeometryAttribute::Type type, int components,
                  draco::DataType dtype, const void *values, size_t nvalues,
                  const uint32_t *point_vertex, uint32_t unique_id, const char *name)
{
    draco::GeometryAttribute ga;
    const int bytes = dtype == draco::DT_FLOAT32 || dtype == draco::DT_UINT32 ? 4 : 1;
    ga.Init(type, nullptr, (int8_t)components, dtype, false, (int64_t)(components * bytes), 0);
    const int id = mesh.AddAttribute(ga, point_vertex == nullptr, (uint32_t)nvalues);
    if (id < 0)
        return -1;
    draco::PointAttribute *att = mesh.attribute(id);
    att->buffer()->Write(0, values, nvalues * (size_t)components * (size_t)bytes);
    if (point_vertex) {
        const size_t npoints = mesh.num_points();
        att->SetExplicitMapping(npoints);
        for (size_t p = 0; p < npoints; p++)
            att->SetPointMapEntry(draco::PointIndex((uint32_t)p),
                                  draco::AttributeValueIndex(point_vertex[p]));
    }
    att->set_unique_id(unique_id);
    std::unique_ptr<draco::AttributeMetadata> md(new draco::AttributeMetadata());
    md->AddEntryString("name", name);
    mesh.AddAttributeMetadata(id, std::move(md));
    return id;
}

// The split points' vertices are all real vertices.
bool points_valid(const ism_draco_input *in)
{
    for (size_t p = 0; in->point_vertex && p < in->npoints; p++)
        if (in->point_vertex[p] >= in->nverts)
            return false;
    return true;
}

bool encode(const ism_draco_input *in, ism_draco_output *out)
{
    const uint32_t *pv = in->point_vertex;
    const size_t npoints = pv ? in->npoints : in->nverts;
    if (in->nverts == 0 || in->ntris == 0 || npoints > 0x7fffffffu) {
        set_error(out, "the mesh is empty or too large");
        return false;
    }
    if (!points_valid(in)) {
        set_error(out, "a point refers to a vertex that does not exist");
        return false;
    }
    if (!pv && (in->point_cell || in->point_sheet)) {
        set_error(out, "triangle labels need the vertices split into points");
        return false;
    }
    draco::Mesh mesh;
    mesh.set_num_points((uint32_t)npoints);
    mesh.SetNumFaces(in->ntris);
    for (size_t t = 0; t < in->ntris; t++) {
        draco::Mesh::Face f;
        for (int k = 0; k < 3; k++) {
            const uint32_t v = in->tri[3 * t + k];
            if (v >= npoints) {
                set_error(out, "a triangle refers to a vertex that does not exist");
                return false;
            }
            f[k] = draco::PointIndex(v);
        }
        mesh.SetFace(draco::FaceIndex((uint32_t)t), f);
    }

    const size_t nv = in->nverts;
    const int pos = add_attribute(mesh, draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32,
                                  in->pos, nv, pv, ISM_DRACO_ID_POSITION, "position");
    int nrm = -1, mean = -1, gauss = -1, cls = -1, cell = -1, sheet = -1;
    if (in->normal)
        nrm = add_attribute(mesh, draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32,
                            in->normal, nv, pv, ISM_DRACO_ID_NORMAL, "normal");
    if (in->mean_curvature)
        mean = add_attribute(mesh, draco::GeometryAttribute::GENERIC, 1, draco::DT_FLOAT32,
                             in->mean_curvature, nv, pv, ISM_DRACO_ID_MEAN_CURVATURE,
                             "mean_curvature");
    if (in->gauss_curvature)
        gauss = add_attribute(mesh, draco::GeometryAttribute::GENERIC, 1, draco::DT_FLOAT32,
                              in->gauss_curvature, nv, pv, ISM_DRACO_ID_GAUSS_CURVATURE,
                              "gauss_curvature");
    if (in->vertex_class)
        cls = add_attribute(mesh, draco::GeometryAttribute::GENERIC, 1, draco::DT_UINT8,
                            in->vertex_class, nv, pv, ISM_DRACO_ID_CLASS, "class");
    if (in->point_cell)
        cell = add_attribute(mesh, draco::GeometryAttribute::GENERIC, 1, draco::DT_UINT32,
                             in->point_cell, npoints, nullptr, ISM_DRACO_ID_CELL, "cell");
    if (in->point_sheet)
        sheet = add_attribute(mesh, draco::GeometryAttribute::GENERIC, 1, draco::DT_UINT8,
                              in->point_sheet, npoints, nullptr, ISM_DRACO_ID_DOUBLE_SHEET,
                              "double_sheet");
    if (pos < 0 || (in->normal && nrm < 0) || (in->mean_curvature && mean < 0) ||
        (in->gauss_curvature && gauss < 0) || (in->vertex_class && cls < 0) ||
        (in->point_cell && cell < 0) || (in->point_sheet && sheet < 0)) {
        set_error(out, "could not add an attribute");
        return false;
    }

    draco::ExpertEncoder enc(mesh);
    const int speed = in->speed < 0 ? ISM_DRACO_DEFAULT_SPEED : in->speed;
    enc.SetSpeedOptions(speed, speed);
    enc.SetTrackEncodedProperties(true);
    enc.SetAttributeQuantization(pos, in->position_bits);
    if (nrm >= 0)
        enc.SetAttributeQuantization(nrm, in->normal_bits);
    if (in->curvature_bits > 0) {
        if (mean >= 0)
            enc.SetAttributeQuantization(mean, in->curvature_bits);
        if (gauss >= 0)
            enc.SetAttributeQuantization(gauss, in->curvature_bits);
    }
    draco::EncoderBuffer buf;
    const draco::Status st = enc.EncodeToBuffer(&buf);
    if (!st.ok()) {
        set_error(out, st.error_msg());
        return false;
    }
    out->len = buf.size();
    out->data = static_cast<unsigned char *>(std::malloc(out->len ? out->len : 1));
    if (!out->data) {
        set_error(out, "out of memory");
        return false;
    }
    std::memcpy(out->data, buf.data(), out->len);
    out->points = enc.num_encoded_points();
    out->faces = enc.num_encoded_faces();
    return true;
}

} // namespace

extern "C" bool ism_draco_encode(const ism_draco_input *in, ism_draco_output *out)
{
    std::memset(out, 0, sizeof *out);
    try {
        return encode(in, out);
    } catch (const std::bad_alloc &) {
        set_error(out, "out of memory");
    } catch (const std::exception &e) {
        set_error(out, e.what());
    } catch (...) {
        set_error(out, "unknown exception");
    }
    std::free(out->data);
    out->data = nullptr;
    out->len = 0;
    return false;
}

// draco_decode_helper.cc — test-only libdraco decoder: bitstream in, arrays out, attributes
// looked up by unique id (GetAttributeByUniqueId) and their metadata names recorded.
#include "tests/unit/proto/draco_decode_helper.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "draco/compression/decode.h"

namespace {

template <typename T>
T *read_attribute(const draco::Mesh &m, uint32_t uid, int comps)
{
    const draco::PointAttribute *a = m.GetAttributeByUniqueId(uid);
    if (!a || a->num_components() != comps)
        return nullptr;
    T *out = static_cast<T *>(std::calloc((size_t)m.num_points() * comps + 1, sizeof(T)));
    for (uint32_t p = 0; out && p < m.num_points(); p++)
        a->ConvertValue<T>(a->mapped_index(draco::PointIndex(p)), comps, out + (size_t)p * comps);
    return out;
}

bool decode(const void *data, size_t len, test_draco_mesh *out, char *err, size_t errlen)
{
    draco::DecoderBuffer buf;
    buf.Init(static_cast<const char *>(data), len);
    draco::Decoder dec;
    auto res = dec.DecodeMeshFromBuffer(&buf);
    if (!res.ok()) {
        std::snprintf(err, errlen, "%s", res.status().error_msg());
        return false;
    }
    std::unique_ptr<draco::Mesh> m = std::move(res).value();
    out->npoints = m->num_points();
    out->nfaces = m->num_faces();
    out->nattributes = m->num_attributes();
    for (int i = 0; i < TEST_DRACO_MAX_IDS; i++)
        out->type_of[i] = -1;
    for (int i = 0; i < m->num_attributes(); i++) {
        const draco::PointAttribute *a = m->attribute(i);
        if (a->unique_id() >= TEST_DRACO_MAX_IDS)
            continue;
        out->type_of[a->unique_id()] = a->attribute_type();
        const draco::AttributeMetadata *md = m->GetAttributeMetadataByAttributeId(i);
        std::string name;
        if (md && md->GetEntryString("name", &name))
            std::snprintf(out->name_of[a->unique_id()], 32, "%s", name.c_str());
    }
    out->faces = static_cast<uint32_t *>(std::calloc(out->nfaces * 3 + 1, sizeof(uint32_t)));
    for (uint32_t f = 0; out->faces && f < m->num_faces(); f++)
        for (int k = 0; k < 3; k++)
            out->faces[3 * f + k] = m->face(draco::FaceIndex(f))[k].value();
    out->pos = read_attribute<float>(*m, 0, 3);
    out->normal = read_attribute<float>(*m, 1, 3);
    out->mean = read_attribute<float>(*m, 2, 1);
    out->gauss = read_attribute<float>(*m, 3, 1);
    out->cls = read_attribute<uint8_t>(*m, 4, 1);
    if (!out->faces || !out->pos) {
        std::snprintf(err, errlen, "no positions or out of memory");
        return false;
    }
    return true;
}

} // namespace

extern "C" bool test_draco_decode(const void *data, size_t len, test_draco_mesh *out,
                                  char *err, size_t errlen)
{
    std::memset(out, 0, sizeof *out);
    try {
        if (decode(data, len, out, err, errlen))
            return true;
    } catch (const std::exception &e) {
        std::snprintf(err, errlen, "%s", e.what());
    }
    test_draco_mesh_free(out);
    return false;
}

extern "C" void test_draco_mesh_free(test_draco_mesh *m)
{
    std::free(m->pos);
    std::free(m->faces);
    std::free(m->normal);
    std::free(m->mean);
    std::free(m->gauss);
    std::free(m->cls);
    std::memset(m, 0, sizeof *m);
}

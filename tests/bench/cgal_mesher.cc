/* cgal_mesher.cc — the CGAL reference of the polygoniser benchmark and the one yardstick that
 * measures every mesh in it. Built by tests/bench/bench_polygonise.py (g++, linked with
 * libism_core.a), so that f is isomesh's own compiled tape (ism_tape_compile) in all modes:
 *
 *   cgal_mesher mesh SURFACE --center X,Y,Z --radius R --angle A --size S --approx D
 *                    [--error E] --out FILE.ply
 *       CGAL's Surface_mesher: make_surface_mesh with Implicit_surface_3 (bounding sphere of
 *       centre X,Y,Z where f < 0 and radius R; intersections bisected to E × R), the default
 *       criteria (angle bound A degrees, radius bound S, distance bound D) and Manifold_tag.
 *       Writes binary PLY (double x y z) and prints {"mesh_s", "vertices", "triangles"}.
 *   cgal_mesher analyse SURFACE --in FILE.ply [--threads N]
 *       Reads a binary little-endian PLY (float or double x y z first, faces as a list of 3)
 *       and prints, from its faces alone: used vertices, edges, boundary and non-manifold
 *       edges, V - E + F, components joined by shared edges; and from f: max/mean |f|/|∇f|
 *       at vertices and at triangle centroids (∇f by the tape's forward-mode gradient;
 *       points where |∇f| <= 1e-6 × the median over the vertices are skipped, as isomesh's
 *       own analysis does).
 *   cgal_mesher eval SURFACE --points X,Y,Z[;X,Y,Z...]
 *       Prints f at the points as a JSON list (the benchmark's check of its numpy formulas).
 *
 * SURFACE is --expr EXPR [--param NAME=VALUE]... [--let NAME=EXPR]... in isomesh's syntax. */
#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Surface_mesh_default_criteria_3.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern "C" {
#include "core/eval/eval.h"
#include "core/expr/expr.h"
}

namespace {

const size_t MAX_NAMED = 64;              // --param and --let each
const uint64_t MAX_PLY_VERTICES = 1u << 26;
const uint64_t MAX_PLY_FACES = 1u << 27;
const double SINGULAR_REL = 1e-6;         // isomesh's analysis default

[[noreturn]] void fail(const std::string &msg)
{
    throw std::runtime_error(msg);
}

/* ---- the surface: isomesh's tape ------------------------------------------------------- */

struct Surface {
    std::string expr;
    std::vector<std::string> param_names, let_names, let_sources;
    std::vector<double> param_values;
    ism_tape *tape = nullptr;

    ~Surface() { ism_tape_free(tape); }

    void compile()
    {
        if (expr.empty())
            fail("give --expr");
        std::vector<ism_param> params;
        for (size_t i = 0; i < param_names.size(); i++)
            params.push_back({param_names[i].c_str(), param_values[i]});
        std::vector<ism_let> lets;
        for (size_t i = 0; i < let_names.size(); i++)
            lets.push_back({let_names[i].c_str(), let_sources[i].c_str()});
        ism_error err;
        std::memset(&err, 0, sizeof err);
        tape = ism_tape_compile(expr.c_str(), params.data(), params.size(), lets.data(),
                                lets.size(), nullptr, &err);
        if (!tape) {
            char buf[512];
            fail(std::string("expression: ") + ism_error_format(&err, buf, sizeof buf));
        }
    }
};

/* One evaluation workspace, owned (a tape's registers; one per thread). */
struct Workspace {
    ism_eval_ws *ws;
    explicit Workspace(const ism_tape *t) : ws(ism_eval_ws_new(t))
    {
        if (!ws)
            fail("out of memory (workspace)");
    }
    ~Workspace() { ism_eval_ws_free(ws); }
    Workspace(const Workspace &) = delete;
    Workspace &operator=(const Workspace &) = delete;
};

/* ---- command line ------------------------------------------------------------------------ */

double parse_number(const std::string &s, const char *what)
{
    char *end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(v))
        fail(std::string("bad number for ") + what + ": '" + s + "'");
    return v;
}

std::vector<double> parse_list(const std::string &s, size_t count, const char *what)
{
    std::vector<double> out;
    size_t start = 0;
    while (true) {
        size_t comma = s.find(',', start);
        out.push_back(parse_number(s.substr(start, comma - start), what));
        if (comma == std::string::npos)
            break;
        start = comma + 1;
    }
    if (out.size() != count)
        fail(std::string("expected ") + std::to_string(count) + " numbers for " + what);
    return out;
}

void split_named(const std::string &item, std::string &name, std::string &value,
                 const char *what)
{
    size_t eq = item.find('=');
    if (eq == 0 || eq == std::string::npos || eq + 1 == item.size())
        fail(std::string("bad ") + what + " '" + item + "' (want NAME=VALUE)");
    name = item.substr(0, eq);
    value = item.substr(eq + 1);
}

struct Args {
    std::string mode;
    Surface surface;
    std::map<std::string, std::string> opts;
};

void parse_args(int argc, char **argv, Args &a)
{
    if (argc < 2)
        fail("usage: cgal_mesher mesh|analyse|eval --expr EXPR [options] (see the source)");
    a.mode = argv[1];
    for (int i = 2; i < argc; i++) {
        std::string key = argv[i];
        if (key.rfind("--", 0) != 0 || i + 1 >= argc)
            fail("expected --option VALUE at '" + key + "'");
        std::string value = argv[++i];
        std::string name, rhs;
        if (key == "--expr") {
            a.surface.expr = value;
        } else if (key == "--param") {
            split_named(value, name, rhs, "--param");
            if (a.surface.param_names.size() >= MAX_NAMED)
                fail("too many --param");
            a.surface.param_names.push_back(name);
            a.surface.param_values.push_back(parse_number(rhs, "--param"));
        } else if (key == "--let") {
            split_named(value, name, rhs, "--let");
            if (a.surface.let_names.size() >= MAX_NAMED)
                fail("too many --let");
            a.surface.let_names.push_back(name);
            a.surface.let_sources.push_back(rhs);
        } else {
            a.opts[key.substr(2)] = value;
        }
    }
}

const std::string &need(const Args &a, const char *key)
{
    auto it = a.opts.find(key);
    if (it == a.opts.end())
        fail(std::string("missing --") + key);
    return it->second;
}

/* ---- PLY -------------------------------------------------------------------------------- */

struct Mesh {
    std::vector<double> pos;     // 3 per vertex
    std::vector<uint32_t> tri;   // 3 per triangle
};

void write_ply(const char *path, const Mesh &m)
{
    FILE *f = std::fopen(path, "wb");
    if (!f)
        fail(std::string("cannot create ") + path);
    std::fprintf(f,
                 "ply\nformat binary_little_endian 1.0\ncomment CGAL Surface_mesher\n"
                 "element vertex %zu\nproperty double x\nproperty double y\nproperty double z\n"
                 "element face %zu\nproperty list uchar int vertex_indices\nend_header\n",
                 m.pos.size() / 3, m.tri.size() / 3);
    std::fwrite(m.pos.data(), sizeof(double), m.pos.size(), f);
    for (size_t t = 0; t < m.tri.size(); t += 3) {
        unsigned char rec[13];
        rec[0] = 3;
        std::memcpy(rec + 1, &m.tri[t], 12);
        std::fwrite(rec, 1, sizeof rec, f);
    }
    if (std::fclose(f) != 0)
        fail(std::string("cannot write ") + path);
}

struct PlyLayout {
    uint64_t nverts = 0, nfaces = 0;
    std::vector<int> vprop_bytes;   // size of each vertex property (4 float, 8 double)
    int index_bytes = 4;
};

/* Reads the header lines this benchmark's writers produce (isomesh, skimage_mc, this file). */
PlyLayout read_ply_header(FILE *f)
{
    PlyLayout L;
    char line[256];
    std::string element;
    bool binary_le = false, face_list = false;
    if (!std::fgets(line, sizeof line, f) || std::strcmp(line, "ply\n") != 0)
        fail("not a PLY file");
    for (int n = 0; n < 64; n++) {
        if (!std::fgets(line, sizeof line, f))
            fail("PLY header ends early");
        char a[64], b[64], c[64], d[64], e[64];
        unsigned long long count;
        if (std::strcmp(line, "end_header\n") == 0) {
            if (!binary_le || !face_list || L.vprop_bytes.size() < 3)
                fail("PLY: need binary_little_endian, x y z and a face list");
            return L;
        }
        if (std::sscanf(line, "format %63s", a) == 1) {
            binary_le = std::strcmp(a, "binary_little_endian") == 0;
        } else if (std::sscanf(line, "element %63s %llu", a, &count) == 2) {
            element = a;
            if (element == "vertex" && count <= MAX_PLY_VERTICES)
                L.nverts = count;
            else if (element == "face" && count <= MAX_PLY_FACES)
                L.nfaces = count;
            else
                fail("PLY: unexpected or too large element " + element);
        } else if (std::sscanf(line, "property list %63s %63s %63s", a, b, c) == 3) {
            if (element != "face" || std::strcmp(a, "uchar") != 0 ||
                (std::strcmp(b, "int") != 0 && std::strcmp(b, "uint") != 0))
                fail("PLY: faces must be 'list uchar int'");
            face_list = true;
        } else if (std::sscanf(line, "property %63s %63s", d, e) == 2) {
            if (element != "vertex")
                fail("PLY: unexpected property");
            if (std::strcmp(d, "float") == 0)
                L.vprop_bytes.push_back(4);
            else if (std::strcmp(d, "double") == 0)
                L.vprop_bytes.push_back(8);
            else
                fail("PLY: vertex properties must be float or double");
        } else if (std::strncmp(line, "comment", 7) != 0) {
            fail("PLY: unexpected header line");
        }
    }
    fail("PLY header too long");
}

Mesh read_ply(const char *path)
{
    FILE *f = std::fopen(path, "rb");
    if (!f)
        fail(std::string("cannot open ") + path);
    Mesh m;
    try {
        PlyLayout L = read_ply_header(f);
        size_t stride = std::accumulate(L.vprop_bytes.begin(), L.vprop_bytes.end(), size_t(0));
        std::vector<unsigned char> rec(stride);
        m.pos.resize(3 * L.nverts);
        for (uint64_t v = 0; v < L.nverts; v++) {
            if (std::fread(rec.data(), 1, stride, f) != stride)
                fail("PLY: vertices end early");
            size_t off = 0;
            for (int k = 0; k < 3; k++) {
                if (L.vprop_bytes[k] == 4) {
                    float x;
                    std::memcpy(&x, &rec[off], 4);
                    m.pos[3 * v + k] = x;
                } else {
                    std::memcpy(&m.pos[3 * v + k], &rec[off], 8);
                }
                off += L.vprop_bytes[k];
            }
        }
        m.tri.resize(3 * L.nfaces);
        for (uint64_t t = 0; t < L.nfaces; t++) {
            unsigned char face[13];
            if (std::fread(face, 1, 13, f) != 13 || face[0] != 3)
                fail("PLY: faces must be triangles");
            std::memcpy(&m.tri[3 * t], face + 1, 12);
            for (int k = 0; k < 3; k++)
                if (m.tri[3 * t + k] >= L.nverts)
                    fail("PLY: face index out of range");
        }
    } catch (...) {
        std::fclose(f);
        throw;
    }
    std::fclose(f);
    return m;
}

/* ---- mesh: CGAL's Surface_mesher ------------------------------------------------------- */

typedef CGAL::Surface_mesh_default_triangulation_3 Tr;
typedef CGAL::Complex_2_in_triangulation_3<Tr> C2t3;
typedef Tr::Geom_traits GT;
typedef GT::Sphere_3 Sphere_3;
typedef GT::Point_3 Point_3;
typedef GT::FT FT;

/* f for CGAL: the tape at a point (one workspace; Surface_mesher runs on one thread). */
struct TapeFunction {
    const ism_tape *tape;
    ism_eval_ws *ws;
    FT operator()(const Point_3 &p) const
    {
        return ism_eval_point(tape, ws, CGAL::to_double(p.x()), CGAL::to_double(p.y()),
                              CGAL::to_double(p.z()));
    }
};
typedef CGAL::Implicit_surface_3<GT, TapeFunction> Implicit;

Mesh complex_to_mesh(const C2t3 &c2t3)
{
    Mesh m;
    std::map<Tr::Vertex_handle, uint32_t> index;
    for (auto it = c2t3.facets_begin(); it != c2t3.facets_end(); ++it) {
        Tr::Cell_handle cell = it->first;
        int opposite = it->second;
        for (int k = 0; k < 4; k++) {
            if (k == opposite)
                continue;
            Tr::Vertex_handle v = cell->vertex(k);
            auto found = index.find(v);
            if (found == index.end()) {
                found = index.emplace(v, uint32_t(m.pos.size() / 3)).first;
                const Point_3 &p = v->point();
                m.pos.push_back(CGAL::to_double(p.x()));
                m.pos.push_back(CGAL::to_double(p.y()));
                m.pos.push_back(CGAL::to_double(p.z()));
            }
            m.tri.push_back(found->second);
        }
    }
    return m;
}

int run_mesh(Args &a)
{
    std::vector<double> c = parse_list(need(a, "center"), 3, "--center");
    double radius = parse_number(need(a, "radius"), "--radius");
    double angle = parse_number(need(a, "angle"), "--angle");
    double size = parse_number(need(a, "size"), "--size");
    double approx = parse_number(need(a, "approx"), "--approx");
    double error = a.opts.count("error") ? parse_number(a.opts["error"], "--error") : 1e-6;
    if (!(radius > 0 && angle > 0 && angle <= 30 && size > 0 && approx > 0 && error > 0))
        fail("need radius, size, approx, error > 0 and 0 < angle <= 30");
    const std::string &out = need(a, "out");
    a.surface.compile();
    Workspace ws(a.surface.tape);
    TapeFunction fn{a.surface.tape, ws.ws};
    if (!(fn(Point_3(c[0], c[1], c[2])) < 0))
        fail("f must be negative at the centre of the bounding sphere");

    auto t0 = std::chrono::steady_clock::now();
    Tr tr;
    C2t3 c2t3(tr);
    Implicit surface(fn, Sphere_3(Point_3(c[0], c[1], c[2]), radius * radius), error);
    CGAL::Surface_mesh_default_criteria_3<Tr> criteria(angle, size, approx);
    CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag());
    Mesh m = complex_to_mesh(c2t3);
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_ply(out.c_str(), m);
    std::printf("{\"mesh_s\":%.6f,\"vertices\":%zu,\"triangles\":%zu}\n", secs,
                m.pos.size() / 3, m.tri.size() / 3);
    return 0;
}

/* ---- analyse: the same figures for every mesh ------------------------------------------- */

struct UnionFind {
    std::vector<uint32_t> parent;
    explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t x)
    {
        while (parent[x] != x)
            x = parent[x] = parent[parent[x]];
        return x;
    }
    void join(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

struct Topology {
    size_t vertices_used = 0, triangles_used = 0, collapsed = 0, edges = 0;
    size_t boundary_edges = 0, nonmanifold_edges = 0, components = 0;
    long euler = 0;
};

bool collapsed(const Mesh &m, size_t t)
{
    const uint32_t *v = &m.tri[3 * t];
    return v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
}

Topology topology(const Mesh &m, std::vector<char> &used)
{
    Topology T;
    size_t nt = m.tri.size() / 3;
    used.assign(m.pos.size() / 3, 0);
    std::vector<std::pair<uint64_t, uint32_t>> edges; // (lo << 32 | hi, triangle)
    edges.reserve(3 * nt);
    for (size_t t = 0; t < nt; t++) {
        if (collapsed(m, t)) {
            T.collapsed++;
            continue;
        }
        T.triangles_used++;
        for (int k = 0; k < 3; k++) {
            uint32_t a = m.tri[3 * t + k], b = m.tri[3 * t + (k + 1) % 3];
            used[a] = 1;
            edges.push_back({(uint64_t(std::min(a, b)) << 32) | std::max(a, b), uint32_t(t)});
        }
    }
    std::sort(edges.begin(), edges.end());
    UnionFind uf(nt);
    for (size_t i = 0; i < edges.size();) {
        size_t j = i + 1;
        while (j < edges.size() && edges[j].first == edges[i].first) {
            uf.join(edges[j].second, edges[i].second);
            j++;
        }
        T.edges++;
        T.boundary_edges += j - i == 1;
        T.nonmanifold_edges += j - i > 2;
        i = j;
    }
    for (size_t t = 0; t < nt; t++)
        T.components += !collapsed(m, t) && uf.find(uint32_t(t)) == t;
    T.vertices_used = size_t(std::count(used.begin(), used.end(), 1));
    T.euler = long(T.vertices_used) - long(T.edges) + long(T.triangles_used);
    return T;
}

/* |f| and |∇f| at n points, on several threads (each with its own workspace). */
void eval_points(const ism_tape *tape, const std::vector<double> &pts, std::vector<double> &fabs_out,
                 std::vector<double> &gnorm_out, unsigned threads)
{
    size_t n = pts.size() / 3;
    fabs_out.assign(n, 0);
    gnorm_out.assign(n, 0);
    auto work = [&](size_t lo, size_t hi) {
        Workspace ws(tape);
        for (size_t i = lo; i < hi; i++) {
            double g[3];
            double fv = ism_eval_gradient(tape, ws.ws, pts[3 * i], pts[3 * i + 1], pts[3 * i + 2], g);
            fabs_out[i] = std::fabs(fv);
            gnorm_out[i] = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        }
    };
    std::vector<std::thread> pool;
    for (unsigned k = 0; k < threads; k++)
        pool.emplace_back(work, n * k / threads, n * (k + 1) / threads);
    for (auto &th : pool)
        th.join();
}

struct Distance {
    double max = 0, mean = 0;
    size_t counted = 0, skipped = 0;
};

Distance distances(const std::vector<double> &fa, const std::vector<double> &gn, double threshold)
{
    Distance d;
    double sum = 0;
    for (size_t i = 0; i < fa.size(); i++) {
        double dist = fa[i] / gn[i];
        if (!(gn[i] > threshold) || !std::isfinite(dist)) {
            d.skipped++;
            continue;
        }
        sum += dist;
        d.max = std::max(d.max, dist);
        d.counted++;
    }
    d.mean = d.counted ? sum / double(d.counted) : 0;
    return d;
}

int run_analyse(Args &a)
{
    unsigned threads = 2;
    if (a.opts.count("threads")) {
        double t = parse_number(a.opts["threads"], "--threads");
        if (!(t >= 1 && t <= 64))
            fail("--threads must be in 1..64");
        threads = unsigned(t);
    }
    a.surface.compile();
    Mesh m = read_ply(need(a, "in").c_str());
    std::vector<char> used;
    Topology T = topology(m, used);

    std::vector<double> vpts, cpts, vf, vg, cf, cg;
    for (size_t v = 0; v < used.size(); v++)
        if (used[v])
            vpts.insert(vpts.end(), &m.pos[3 * v], &m.pos[3 * v + 3]);
    for (size_t t = 0; t < m.tri.size() / 3; t++) {
        if (collapsed(m, t))
            continue;
        for (int i = 0; i < 3; i++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += m.pos[3 * m.tri[3 * t + k] + i] / 3;
            cpts.push_back(s);
        }
    }
    eval_points(a.surface.tape, vpts, vf, vg, threads);
    eval_points(a.surface.tape, cpts, cf, cg, threads);
    std::vector<double> sorted;
    for (double g : vg)
        if (std::isfinite(g))
            sorted.push_back(g);
    double median = 0;
    if (!sorted.empty()) {
        std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
        median = sorted[sorted.size() / 2];
    }
    Distance dv = distances(vf, vg, SINGULAR_REL * median);
    Distance dc = distances(cf, cg, SINGULAR_REL * median);
    std::printf("{\"vertices\":%zu,\"triangles\":%zu,\"vertices_used\":%zu,"
                "\"triangles_used\":%zu,\"collapsed_triangles\":%zu,\"edges\":%zu,"
                "\"boundary_edges\":%zu,\"nonmanifold_edges\":%zu,\"euler\":%ld,"
                "\"components\":%zu,\"max_dist_vertex\":%.6g,\"mean_dist_vertex\":%.6g,"
                "\"max_dist_centroid\":%.6g,\"mean_dist_centroid\":%.6g,"
                "\"skipped_vertices\":%zu,\"skipped_centroids\":%zu}\n",
                m.pos.size() / 3, m.tri.size() / 3, T.vertices_used, T.triangles_used,
                T.collapsed, T.edges, T.boundary_edges, T.nonmanifold_edges, T.euler,
                T.components, dv.max, dv.mean, dc.max, dc.mean, dv.skipped, dc.skipped);
    return 0;
}

/* ---- eval ------------------------------------------------------------------------------- */

int run_eval(Args &a)
{
    a.surface.compile();
    Workspace ws(a.surface.tape);
    const std::string &text = need(a, "points");
    std::printf("[");
    size_t start = 0, n = 0;
    while (start <= text.size() && n < 10000) {
        size_t semi = text.find(';', start);
        std::vector<double> p = parse_list(text.substr(start, semi - start), 3, "--points");
        double fv = ism_eval_point(a.surface.tape, ws.ws, p[0], p[1], p[2]);
        std::printf("%s%.17g", n++ ? "," : "", fv);
        if (semi == std::string::npos)
            break;
        start = semi + 1;
    }
    std::printf("]\n");
    return 0;
}

} // namespace

int main(int argc, char **argv)
{
    static_assert(sizeof(double) == 8, "PLY doubles");
    const uint16_t probe = 1;
    unsigned char low;
    std::memcpy(&low, &probe, 1);
    try {
        if (low != 1)
            fail("this program writes and reads little-endian PLY on little-endian hosts only");
        Args a;
        parse_args(argc, argv, a);
        if (a.mode == "mesh")
            return run_mesh(a);
        if (a.mode == "analyse")
            return run_analyse(a);
        if (a.mode == "eval")
            return run_eval(a);
        fail("unknown mode '" + a.mode + "' (mesh, analyse or eval)");
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cgal_mesher: %s\n", e.what());
        return 2;
    }
}

// gltf_check - an independent reader of the .glb files the decoder writes
// (tests only; never shipped).
//
//   gltf_check FILE.glb [--quiet]
//
// Loads the file with tinygltf (LoadBinaryFromFile, every top-level section
// required) and fails on any error or warning, then checks what a strict
// validator would:
//   - the GLB container: magic, version 2, length = file size, JSON chunk
//     first and BIN chunk second, both 4-byte aligned lengths;
//   - buffers: one GLB-stored buffer, byteLength within the BIN chunk and
//     at most 3 bytes short of it;
//   - buffer views: inside their buffer, 4-byte aligned offsets, byteStride
//     in [4, 252] and a multiple of 4, targets ARRAY_BUFFER/ELEMENT_ARRAY_BUFFER,
//     no byteStride on index views, a stride on views shared by several
//     vertex accessors;
//   - accessors: valid component type/type, count >= 1, byteOffset aligned to
//     the component size, every element inside its buffer view, min/max (if
//     present, and required on POSITION) equal to the data as float32;
//   - meshes: every primitive has POSITION, attributes of equal count,
//     indices (if any) UNSIGNED_BYTE/SHORT/INT SCALAR on an index view, all
//     below the vertex count, a multiple of 3 for triangles; NORMAL of unit
//     length (1e-3); material, mesh, node and scene references in range;
//     node matrices of 16 numbers.
// Prints "ok: N primitives, V vertices, T triangles" and exits 0, or lists
// every problem on stderr and exits 1 (2 on usage or load failure).
//
// Build: make gltf-check-tool (tests/tools/gltf_check.mk); needs the Debian
// packages libtinygltf-dev and nlohmann-json3-dev (tiny_gltf.h includes
// <nlohmann/json.hpp>, which libtinygltf-dev does not pull in).

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

namespace {

int g_problems = 0;

void problem(const std::string &what)
{
    if (g_problems < 50)
        std::fprintf(stderr, "gltf_check: %s\n", what.c_str());
    g_problems++;
}

uint32_t rd32(const unsigned char *p)
{
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// the GLB container, read by hand (tinygltf is lenient about some of it)
void check_container(const std::vector<unsigned char> &f)
{
    if (f.size() < 20) {
        problem("file shorter than a GLB header and one chunk header");
        return;
    }
    if (std::memcmp(f.data(), "glTF", 4) != 0)
        problem("magic is not glTF");
    if (rd32(&f[4]) != 2)
        problem("GLB version " + std::to_string(rd32(&f[4])) + ", expected 2");
    if (rd32(&f[8]) != f.size())
        problem("header length " + std::to_string(rd32(&f[8])) + " != file size " + std::to_string(f.size()));
    if (f.size() % 4 != 0)
        problem("file size not a multiple of 4");
    size_t pos = 12;
    int chunk = 0;
    while (pos + 8 <= f.size()) {
        uint32_t len = rd32(&f[pos]), type = rd32(&f[pos + 4]);
        if (len % 4 != 0)
            problem("chunk " + std::to_string(chunk) + " length " + std::to_string(len) + " not 4-byte aligned");
        if (pos + 8 + len > f.size()) {
            problem("chunk " + std::to_string(chunk) + " runs past the end of the file");
            return;
        }
        if (chunk == 0 && type != 0x4E4F534Au)
            problem("first chunk is not JSON");
        if (chunk == 1 && type != 0x004E4942u)
            problem("second chunk is not BIN");
        if (chunk == 0) { // JSON padding must be spaces
            size_t e = pos + 8 + len;
            while (e > pos + 8 && f[e - 1] == ' ')
                e--;
            if (pos + 8 + len - e > 3)
                problem("JSON chunk has more than 3 padding spaces");
            if (e == pos + 8 || f[e - 1] != '}')
                problem("JSON chunk does not end with '}' before its padding");
        }
        pos += 8 + len;
        chunk++;
    }
    if (pos != f.size())
        problem("trailing bytes after the last chunk");
    if (chunk < 1)
        problem("no JSON chunk");
}

bool component_ok(int ct)
{
    switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return true;
    default:
        return false;
    }
}

// component c of element i as double (nullptr data: out of range, reported already)
double component(const tinygltf::Model &m, const tinygltf::Accessor &a, size_t i, int c)
{
    const tinygltf::BufferView &bv = m.bufferViews[size_t(a.bufferView)];
    const std::vector<unsigned char> &d = m.buffers[size_t(bv.buffer)].data;
    size_t cs = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType)));
    size_t off = bv.byteOffset + a.byteOffset + i * size_t(a.ByteStride(bv)) + size_t(c) * cs;
    const unsigned char *p = d.data() + off;
    switch (a.componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
        return double(int8_t(p[0]));
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return double(p[0]);
    case TINYGLTF_COMPONENT_TYPE_SHORT:
        return double(int16_t(uint16_t(p[0] | p[1] << 8)));
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return double(uint16_t(p[0] | p[1] << 8));
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return double(rd32(p));
    default: {
        uint32_t u = rd32(p);
        float f;
        std::memcpy(&f, &u, sizeof f);
        return double(f);
    }
    }
}

// accessor i's structure; returns whether its data may be read
bool check_accessor(const tinygltf::Model &m, size_t i, const std::vector<int> &view_users)
{
    const tinygltf::Accessor &a = m.accessors[i];
    std::string name = "accessor " + std::to_string(i);
    if (!component_ok(a.componentType)) {
        problem(name + ": bad componentType " + std::to_string(a.componentType));
        return false;
    }
    int nc = tinygltf::GetNumComponentsInType(uint32_t(a.type));
    if (nc <= 0) {
        problem(name + ": bad type");
        return false;
    }
    if (a.count < 1)
        problem(name + ": count < 1");
    if (a.sparse.isSparse) {
        problem(name + ": sparse accessors are not checked");
        return false;
    }
    if (a.bufferView < 0 || size_t(a.bufferView) >= m.bufferViews.size()) {
        problem(name + ": no valid bufferView");
        return false;
    }
    const tinygltf::BufferView &bv = m.bufferViews[size_t(a.bufferView)];
    size_t cs = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType)));
    int stride = a.ByteStride(bv);
    if (stride <= 0) {
        problem(name + ": byteStride of its view is not a multiple of the component size");
        return false;
    }
    if (a.byteOffset % cs != 0 || (bv.byteOffset + a.byteOffset) % cs != 0)
        problem(name + ": byteOffset not aligned to the component size");
    size_t elem = cs * size_t(nc);
    if (bv.byteStride != 0 && size_t(bv.byteStride) < elem)
        problem(name + ": view stride smaller than an element");
    if (a.count >= 1 && a.byteOffset + size_t(stride) * (a.count - 1) + elem > bv.byteLength) {
        problem(name + ": elements run past the end of buffer view " + std::to_string(a.bufferView));
        return false;
    }
    if (bv.target == TINYGLTF_TARGET_ARRAY_BUFFER && view_users[size_t(a.bufferView)] > 1 && bv.byteStride == 0)
        problem(name + ": its vertex view is shared by several accessors but has no byteStride");
    // min/max equal to the data (float32 for float accessors, as a validator compares them)
    bool has_min = !a.minValues.empty(), has_max = !a.maxValues.empty();
    if ((has_min && a.minValues.size() != size_t(nc)) || (has_max && a.maxValues.size() != size_t(nc)))
        problem(name + ": min/max has the wrong number of components");
    else if ((has_min || has_max) && a.count >= 1) {
        for (int c = 0; c < nc; c++) {
            double lo = component(m, a, 0, c), hi = lo;
            for (size_t k = 1; k < a.count; k++) {
                double v = component(m, a, k, c);
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
            bool f = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
            auto same = [f](double declared, double actual) {
                return f ? float(declared) == float(actual) : declared == actual;
            };
            if (has_min && !same(a.minValues[size_t(c)], lo))
                problem(name + ": min[" + std::to_string(c) + "] = " + std::to_string(a.minValues[size_t(c)]) +
                        ", data min " + std::to_string(lo));
            if (has_max && !same(a.maxValues[size_t(c)], hi))
                problem(name + ": max[" + std::to_string(c) + "] = " + std::to_string(a.maxValues[size_t(c)]) +
                        ", data max " + std::to_string(hi));
        }
    }
    return true;
}

} // namespace

int main(int argc, char **argv)
{
    bool quiet = false;
    const char *path = nullptr;
    for (int i = 1; i < argc; i++) {
        if (std::strcmp(argv[i], "--quiet") == 0)
            quiet = true;
        else if (path == nullptr && argv[i][0] != '-')
            path = argv[i];
        else {
            path = nullptr;
            break;
        }
    }
    if (path == nullptr) {
        std::fprintf(stderr, "usage: gltf_check FILE.glb [--quiet]\n");
        return 2;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        std::fprintf(stderr, "gltf_check: cannot open %s\n", path);
        return 2;
    }
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    check_container(bytes);

    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    bool loaded = loader.LoadBinaryFromFile(&m, &err, &warn, path, tinygltf::REQUIRE_ALL);
    if (!warn.empty())
        problem("tinygltf warning: " + warn);
    if (!err.empty())
        problem("tinygltf error: " + err);
    if (!loaded) {
        std::fprintf(stderr, "gltf_check: %s: tinygltf cannot load it\n", path);
        return 2;
    }

    if (m.asset.version != "2.0")
        problem("asset.version is \"" + m.asset.version + "\"");
    // buffers
    size_t bin_chunk = 0;
    if (bytes.size() >= 20) {
        size_t jl = rd32(&bytes[12]);
        if (20 + jl + 8 <= bytes.size())
            bin_chunk = rd32(&bytes[20 + jl]);
    }
    if (m.buffers.size() != 1)
        problem("expected one buffer, found " + std::to_string(m.buffers.size()));
    for (size_t i = 0; i < m.buffers.size(); i++) {
        const tinygltf::Buffer &b = m.buffers[i];
        if (!b.uri.empty())
            problem("buffer " + std::to_string(i) + " has a uri: not GLB-stored");
        if (b.data.size() > bin_chunk || bin_chunk - b.data.size() > 3)
            problem("buffer " + std::to_string(i) + " byteLength " + std::to_string(b.data.size()) +
                    " does not match the BIN chunk (" + std::to_string(bin_chunk) + ")");
    }
    // buffer views
    std::vector<int> view_users(m.bufferViews.size(), 0);
    for (const tinygltf::Accessor &a : m.accessors)
        if (a.bufferView >= 0 && size_t(a.bufferView) < view_users.size())
            view_users[size_t(a.bufferView)]++;
    std::vector<bool> view_ok(m.bufferViews.size(), true);
    for (size_t i = 0; i < m.bufferViews.size(); i++) {
        const tinygltf::BufferView &v = m.bufferViews[i];
        std::string name = "bufferView " + std::to_string(i);
        if (v.buffer < 0 || size_t(v.buffer) >= m.buffers.size()) {
            problem(name + ": bad buffer");
            view_ok[i] = false;
            continue;
        }
        if (v.byteLength < 1)
            problem(name + ": byteLength < 1");
        if (v.byteOffset + v.byteLength > m.buffers[size_t(v.buffer)].data.size()) {
            problem(name + ": runs past the end of its buffer");
            view_ok[i] = false;
        }
        if (v.byteOffset % 4 != 0)
            problem(name + ": byteOffset not 4-byte aligned");
        if (v.byteStride != 0 && (v.byteStride < 4 || v.byteStride > 252 || v.byteStride % 4 != 0))
            problem(name + ": byteStride " + std::to_string(v.byteStride) + " outside [4, 252] or not a multiple of 4");
        if (v.target != 0 && v.target != TINYGLTF_TARGET_ARRAY_BUFFER && v.target != TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER)
            problem(name + ": bad target " + std::to_string(v.target));
        if (v.target == TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER && v.byteStride != 0)
            problem(name + ": index view with a byteStride");
    }
    // accessors
    std::vector<bool> acc_ok(m.accessors.size(), false);
    for (size_t i = 0; i < m.accessors.size(); i++) {
        const tinygltf::Accessor &a = m.accessors[i];
        if (a.bufferView >= 0 && size_t(a.bufferView) < view_ok.size() && !view_ok[size_t(a.bufferView)])
            continue; // reported with the view
        acc_ok[i] = check_accessor(m, i, view_users);
    }
    // materials
    for (size_t i = 0; i < m.materials.size(); i++) {
        const std::vector<double> &c = m.materials[i].pbrMetallicRoughness.baseColorFactor;
        for (double x : c)
            if (!(x >= 0.0 && x <= 1.0))
                problem("material " + std::to_string(i) + ": baseColorFactor outside [0, 1]");
    }
    // meshes
    size_t nprim = 0, nvert = 0, ntri = 0, nface_extras = 0;
    for (size_t mi = 0; mi < m.meshes.size(); mi++) {
        const tinygltf::Mesh &mesh = m.meshes[mi];
        if (mesh.primitives.empty())
            problem("mesh " + std::to_string(mi) + " has no primitives");
        for (size_t pi = 0; pi < mesh.primitives.size(); pi++) {
            const tinygltf::Primitive &p = mesh.primitives[pi];
            std::string name = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
            nprim++;
            if (p.extras.IsObject() && p.extras.Has("face") && p.extras.Get("face").IsInt())
                nface_extras++;
            if (p.material >= 0 && size_t(p.material) >= m.materials.size())
                problem(name + ": material out of range");
            auto pos_it = p.attributes.find("POSITION");
            if (pos_it == p.attributes.end()) {
                problem(name + ": no POSITION");
                continue;
            }
            size_t vcount = 0;
            bool attrs_ok = true;
            for (const auto &kv : p.attributes) {
                if (kv.second < 0 || size_t(kv.second) >= m.accessors.size()) {
                    problem(name + ": attribute " + kv.first + " accessor out of range");
                    attrs_ok = false;
                    continue;
                }
                const tinygltf::Accessor &a = m.accessors[size_t(kv.second)];
                if (kv.first == "POSITION") {
                    vcount = a.count;
                    if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
                        problem(name + ": POSITION is not float VEC3");
                    if (a.minValues.empty() || a.maxValues.empty())
                        problem(name + ": POSITION without min/max");
                }
                const tinygltf::BufferView *bv =
                    a.bufferView >= 0 && size_t(a.bufferView) < m.bufferViews.size() ? &m.bufferViews[size_t(a.bufferView)] : nullptr;
                if (bv != nullptr && bv->target == TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER)
                    problem(name + ": attribute " + kv.first + " on an index view");
            }
            if (!attrs_ok)
                continue;
            for (const auto &kv : p.attributes)
                if (m.accessors[size_t(kv.second)].count != vcount)
                    problem(name + ": attribute " + kv.first + " count differs from POSITION's");
            nvert += vcount;
            auto n_it = p.attributes.find("NORMAL");
            if (n_it != p.attributes.end() && acc_ok[size_t(n_it->second)]) {
                const tinygltf::Accessor &a = m.accessors[size_t(n_it->second)];
                if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
                    problem(name + ": NORMAL is not float VEC3");
                else
                    for (size_t k = 0; k < a.count; k++) {
                        double x = component(m, a, k, 0), y = component(m, a, k, 1), z = component(m, a, k, 2);
                        double len = std::sqrt(x * x + y * y + z * z);
                        if (!(std::fabs(len - 1.0) <= 1e-3)) {
                            problem(name + ": normal " + std::to_string(k) + " has length " + std::to_string(len));
                            break;
                        }
                    }
            }
            size_t icount = vcount;
            if (p.indices >= 0) {
                if (size_t(p.indices) >= m.accessors.size()) {
                    problem(name + ": indices accessor out of range");
                    continue;
                }
                const tinygltf::Accessor &a = m.accessors[size_t(p.indices)];
                icount = a.count;
                if (a.type != TINYGLTF_TYPE_SCALAR ||
                    (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                     a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                     a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                    problem(name + ": indices are not an unsigned SCALAR");
                else if (acc_ok[size_t(p.indices)]) {
                    const tinygltf::BufferView &bv = m.bufferViews[size_t(a.bufferView)];
                    if (bv.target != TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER)
                        problem(name + ": indices view target is not ELEMENT_ARRAY_BUFFER");
                    if (bv.byteStride != 0)
                        problem(name + ": indices view has a byteStride");
                    for (size_t k = 0; k < a.count; k++) {
                        double v = component(m, a, k, 0);
                        if (!(v < double(vcount))) {
                            problem(name + ": index " + std::to_string(k) + " = " + std::to_string(v) +
                                    " >= vertex count " + std::to_string(vcount));
                            break;
                        }
                    }
                }
            }
            if (p.mode == TINYGLTF_MODE_TRIANGLES || p.mode == -1) {
                if (icount % 3 != 0)
                    problem(name + ": triangle list of " + std::to_string(icount) + " indices");
                ntri += icount / 3;
            }
        }
    }
    // nodes and scenes
    for (size_t i = 0; i < m.nodes.size(); i++) {
        const tinygltf::Node &n = m.nodes[i];
        if (n.mesh >= 0 && size_t(n.mesh) >= m.meshes.size())
            problem("node " + std::to_string(i) + ": mesh out of range");
        if (!n.matrix.empty() && n.matrix.size() != 16)
            problem("node " + std::to_string(i) + ": matrix of " + std::to_string(n.matrix.size()) + " numbers");
        for (int c : n.children)
            if (c < 0 || size_t(c) >= m.nodes.size())
                problem("node " + std::to_string(i) + ": child out of range");
    }
    if (m.defaultScene >= 0 && size_t(m.defaultScene) >= m.scenes.size())
        problem("scene out of range");
    for (size_t i = 0; i < m.scenes.size(); i++)
        for (int n : m.scenes[i].nodes)
            if (n < 0 || size_t(n) >= m.nodes.size())
                problem("scene " + std::to_string(i) + ": node out of range");

    if (g_problems > 0) {
        std::fprintf(stderr, "gltf_check: %s: %d problem(s)\n", path, g_problems);
        return 1;
    }
    if (!quiet && !m.asset.generator.empty())
        std::printf("%s: generator \"%s\", %zu materials, %zu accessors, %zu primitives with extras.face\n", path,
                    m.asset.generator.c_str(), m.materials.size(), m.accessors.size(), nface_extras);
    std::printf("ok: %zu primitives, %zu vertices, %zu triangles\n", nprim, nvert, ntri);
    return 0;
}

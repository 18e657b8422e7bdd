// occt_oracle - an independent test oracle for curvemesh, built on Open CASCADE (OCCT).
//
// curvemesh rebuilds every face of an IGES model from its boundary curves.  To judge
// that result we need answers that do not come from curvemesh's own IGES reader or
// geometry kernels: what the model contains, how far a set of points is from the real
// (trimmed) faces, and how far a decoded triangle mesh is from the model in both
// directions.  This tool gives those answers using OCCT only.
//
//   occt_oracle info     MODEL.igs
//   occt_oracle points   MODEL.igs POINTS.xyz [--tol-rel 1e-6]
//   occt_oracle mesh-dev MODEL.igs MESH.stl   [--defl-rel 1e-4]
//   occt_oracle sample   MODEL.igs OUT.xyz    [--per-face N]
//   occt_oracle write-stl MODEL.igs OUT.stl   [--defl-rel 1e-4]   (hidden: test meshes)
//
// Output: machine-readable "key value" lines on stdout, human-readable lines start
// with "# ".  Exit status: 0 success, 1 a check failed (points farther than tol),
// 2 usage or input error.  Diagnostics go to stderr.  OCCT itself prints to stdout in
// places (IGES load reports, messenger), so fd 1 is redirected to stderr at start-up
// and our own results go to a private duplicate of the original stdout.
//
// See tests/oracle/README.md for the method and the OCCT pitfalls met.

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Surface.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Poly_Triangulation.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Trsf.hxx>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

namespace {

// ---------------------------------------------------------------------------------
// Output, errors, timing
// ---------------------------------------------------------------------------------

FILE* g_out = stdout;   // our results; a duplicate of the original stdout (see main)
bool g_verbose = false;

// Usage and input errors both end the run with status 2; the message says which.
struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

std::string strf(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string strf(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    char buf[1024];
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return buf;
}

// "key value" line.  Values are printed with %.10g: enough to compare distances at
// 1e-6 relative tolerance, short enough to read.  Sample coordinates use %.17g.
void kv(const char* key, double v) { fprintf(g_out, "%s %.10g\n", key, v); }
void kv(const char* key, long long v) { fprintf(g_out, "%s %lld\n", key, v); }
void note(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void note(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs("# ", g_out);
    vfprintf(g_out, fmt, ap);
    fputc('\n', g_out);
    va_end(ap);
}
void warn(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void warn(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs("occt_oracle: warning: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

class Stopwatch {
public:
    Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    }
private:
    std::chrono::steady_clock::time_point t0_;
};

// Human-readable text from an OCCT exception (GetMessageString may be empty).
std::string occt_what(const Standard_Failure& e) {
    const char* m = e.GetMessageString();
    std::string s = e.DynamicType()->Name();
    if (m && *m) s += std::string(": ") + m;
    return s;
}

// ---------------------------------------------------------------------------------
// Small 3D helpers
// ---------------------------------------------------------------------------------

struct V3 {
    double x = 0, y = 0, z = 0;
    V3() = default;
    V3(double a, double b, double c) : x(a), y(b), z(c) {}
    explicit V3(const gp_Pnt& p) : x(p.X()), y(p.Y()), z(p.Z()) {}
    gp_Pnt pnt() const { return gp_Pnt(x, y, z); }
    double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
inline V3 operator-(const V3& a, const V3& b) { return V3(a.x - b.x, a.y - b.y, a.z - b.z); }
inline V3 operator+(const V3& a, const V3& b) { return V3(a.x + b.x, a.y + b.y, a.z + b.z); }
inline V3 operator*(double s, const V3& a) { return V3(s * a.x, s * a.y, s * a.z); }
inline double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(const V3& a, const V3& b) {
    return V3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
inline double norm(const V3& a) { return std::sqrt(dot(a, a)); }

// Axis-aligned box.  Empty boxes have lo > hi.
struct Box3 {
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
    double hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    void add(const V3& p) {
        for (int a = 0; a < 3; a++) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    }
    void add(const Box3& b) {
        for (int a = 0; a < 3; a++) {
            lo[a] = std::min(lo[a], b.lo[a]);
            hi[a] = std::max(hi[a], b.hi[a]);
        }
    }
    double centre(int a) const { return 0.5 * (lo[a] + hi[a]); }
    // Euclidean distance from p to the box (0 inside): a lower bound of the distance
    // to anything the box contains.
    double dist(const V3& p) const {
        double s = 0;
        for (int a = 0; a < 3; a++) {
            double d = 0;
            if (p[a] < lo[a]) d = lo[a] - p[a];
            else if (p[a] > hi[a]) d = p[a] - hi[a];
            s += d * d;
        }
        return std::sqrt(s);
    }
};

// ---------------------------------------------------------------------------------
// Bounding-volume hierarchy over boxes, written for this tool.
//
// Used twice: over the faces of the model (items = faces, exact distance computed by
// the caller) and over the triangles of an STL mesh.  nearest() visits items in a
// near-first order and skips every subtree whose box is not closer than the current
// best distance, so the result is the exact minimum as long as the item boxes really
// contain their items.
// ---------------------------------------------------------------------------------

class Bvh {
public:
    void build(const std::vector<Box3>& item_boxes) {
        boxes_ = item_boxes;
        order_.resize(boxes_.size());
        for (size_t i = 0; i < order_.size(); i++) order_[i] = static_cast<int>(i);
        nodes_.clear();
        if (!order_.empty()) build_rec(0, static_cast<int>(order_.size()));
    }

    // visit(item, lower_bound, best) may lower `best`; returning true stops the search.
    template <class Visit>
    void nearest(const V3& p, double& best, Visit&& visit) const {
        if (nodes_.empty()) return;
        struct Entry { int node; double lb; };
        Entry stack[128];
        int top = 0;
        stack[top++] = {0, nodes_[0].box.dist(p)};
        while (top > 0) {
            Entry e = stack[--top];
            if (e.lb >= best) continue;
            const Node& n = nodes_[static_cast<size_t>(e.node)];
            if (n.count > 0) {
                for (int k = n.first; k < n.first + n.count; k++) {
                    int item = order_[static_cast<size_t>(k)];
                    double lb = boxes_[static_cast<size_t>(item)].dist(p);
                    if (lb >= best) continue;
                    if (visit(item, lb, best)) return;
                }
                continue;
            }
            double la = nodes_[static_cast<size_t>(n.left)].box.dist(p);
            double lr = nodes_[static_cast<size_t>(n.right)].box.dist(p);
            // push the farther child first so the nearer one is searched first
            if (top + 2 > 128) throw std::runtime_error("BVH too deep");
            if (la <= lr) {
                stack[top++] = {n.right, lr};
                stack[top++] = {n.left, la};
            } else {
                stack[top++] = {n.left, la};
                stack[top++] = {n.right, lr};
            }
        }
    }

private:
    struct Node {
        Box3 box;
        int first = 0, count = 0;   // leaf: items order_[first .. first+count)
        int left = -1, right = -1;  // inner node
    };

    int build_rec(int first, int last) {
        int id = static_cast<int>(nodes_.size());
        nodes_.emplace_back();
        Box3 box, cbox;  // cbox: box of item centres, chooses the split axis
        for (int k = first; k < last; k++) {
            const Box3& b = boxes_[static_cast<size_t>(order_[static_cast<size_t>(k)])];
            box.add(b);
            cbox.add(V3(b.centre(0), b.centre(1), b.centre(2)));
        }
        nodes_[static_cast<size_t>(id)].box = box;
        const int kLeaf = 4;
        int axis = 0;
        for (int a = 1; a < 3; a++)
            if (cbox.hi[a] - cbox.lo[a] > cbox.hi[axis] - cbox.lo[axis]) axis = a;
        if (last - first <= kLeaf || !(cbox.hi[axis] > cbox.lo[axis])) {
            nodes_[static_cast<size_t>(id)].first = first;
            nodes_[static_cast<size_t>(id)].count = last - first;
            return id;
        }
        // median split on centres: depth stays ~log2(n) whatever the distribution
        int mid = first + (last - first) / 2;
        std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + last,
                         [&](int a, int b) {
                             return boxes_[static_cast<size_t>(a)].centre(axis) <
                                    boxes_[static_cast<size_t>(b)].centre(axis);
                         });
        int l = build_rec(first, mid);
        int r = build_rec(mid, last);
        nodes_[static_cast<size_t>(id)].left = l;
        nodes_[static_cast<size_t>(id)].right = r;
        return id;
    }

    std::vector<Box3> boxes_;
    std::vector<int> order_;
    std::vector<Node> nodes_;
};

// ---------------------------------------------------------------------------------
// Model reading
// ---------------------------------------------------------------------------------

struct Model {
    TopoDS_Shape shape;
    TopTools_IndexedMapOfShape faces;  // OCCT face index = map index (1-based)
    std::vector<Box3> face_boxes;      // [index-1]: a box that contains the face (not tight)
    Box3 box;                          // tight box of all faces
    double diag = 0;
    int optimal_boxes = 0;             // faces whose optimal box was needed for `box`
    std::string unit_name;
    int unit_flag = 0;
};

void check_readable_file(const char* path, const char* what) {
    struct stat st;
    if (stat(path, &st) != 0)
        throw InputError(strf("cannot open %s '%s': %s", what, path, strerror(errno)));
    if (S_ISDIR(st.st_mode)) throw InputError(strf("%s '%s' is a directory", what, path));
    FILE* f = fopen(path, "rb");
    if (!f) throw InputError(strf("cannot open %s '%s': %s", what, path, strerror(errno)));
    fclose(f);
}

// Cheap sniff so that a wrong file gives a clear message instead of whatever the IGES
// parser makes of it: fixed-format IGES has the section letter in column 73 and the
// file starts with the Start (S) or, in some exporters, the Global (G) section.
// Compressed ('C') and binary ('B') IGES are not supported by OCCT either.
void sniff_iges(const char* path) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line.empty())
        throw InputError(strf("'%s' is empty, not an IGES file", path));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.size() < 73 || (line[72] != 'S' && line[72] != 'G'))
        throw InputError(strf("'%s' is not a fixed-format IGES file (line 1 has no 'S' or 'G' "
                              "section letter in column 73)", path));
}

void set_static(const char* name, const char* value) {
    if (!Interface_Static::SetCVal(name, value))
        warn("could not set OCCT parameter %s=%s", name, value);
}
void set_static(const char* name, int value) {
    if (!Interface_Static::SetIVal(name, value))
        warn("could not set OCCT parameter %s=%d", name, value);
}

inline double sq(double x) { return x * x; }

Box3 to_box3(const Bnd_Box& b) {
    Box3 r;
    if (b.IsVoid()) return r;
    b.Get(r.lo[0], r.lo[1], r.lo[2], r.hi[0], r.hi[1], r.hi[2]);
    return r;
}

// A box that contains face i.  BRepBndLib::Add is fast and, for analytic and B-spline
// surfaces, conservative (exact formulas, convex hull of the poles).  For the other
// surface types (revolution, extrusion, offset, B-splines trimmed outside their own
// domain) OCCT only samples a grid, which can cut off a bulge between samples; those
// boxes get a margin of 10% of their diagonal, far more than the sampling error.
Box3 containing_box(const TopoDS_Face& f) {
    Bnd_Box b;
    BRepBndLib::Add(f, b, Standard_False);  // includes the face/edge tolerances
    if (b.IsVoid()) throw Standard_Failure("empty box");
    bool conservative = false;
    BRepAdaptor_Surface bs(f);
    switch (bs.GetType()) {
    case GeomAbs_Plane:
    case GeomAbs_Cylinder:
    case GeomAbs_Cone:
    case GeomAbs_Sphere:
    case GeomAbs_Torus:
        conservative = true;
        break;
    case GeomAbs_BSplineSurface: {
        double a0, a1, b0, b1;
        bs.BSpline()->Bounds(a0, a1, b0, b1);
        const double pt = Precision::PConfusion();
        conservative = bs.FirstUParameter() >= a0 - pt && bs.LastUParameter() <= a1 + pt &&
                       bs.FirstVParameter() >= b0 - pt && bs.LastVParameter() <= b1 + pt;
        break;
    }
    default:
        break;
    }
    if (!conservative) b.Enlarge(0.1 * std::sqrt(b.SquareExtent()));
    return to_box3(b);
}

// Containing boxes for every face, then the tight model box.
//
// AddOptimal (exact geometry, no tolerance padding) is what "tight" means, but it is
// slow on some surfaces (~25 ms for a surface of revolution: 6 minutes for the
// 27734-face CATIA assembly).  Only faces that can touch the model box matter: for each
// of the 6 directions, faces are taken in decreasing order of their containing box's
// reach in that direction, and the scan stops as soon as that reach is inside the
// tight box built so far -- no later face can extend it, because a face lies inside
// its containing box.  The result equals the union of all the optimal face boxes.
void compute_boxes(Model& m) {
    const int n = m.faces.Extent();
    m.face_boxes.assign(static_cast<size_t>(n), Box3());
    Box3 loose_all;
    for (int i = 0; i < n; i++) {
        const TopoDS_Face& f = TopoDS::Face(m.faces(i + 1));
        try {
            m.face_boxes[static_cast<size_t>(i)] = containing_box(f);
        } catch (const Standard_Failure& e) {
            warn("face %d: no bounding box (%s)", i + 1, occt_what(e).c_str());
        }
        loose_all.add(m.face_boxes[static_cast<size_t>(i)]);
    }
    if (!(loose_all.lo[0] <= loose_all.hi[0]))
        throw InputError("no face has a bounding box");
    // Faces without a box (failed above) get the box of everything: safe for pruning.
    for (Box3& b : m.face_boxes)
        if (!(b.lo[0] <= b.hi[0])) b = loose_all;

    std::vector<char> done(static_cast<size_t>(n), 0);
    std::vector<int> order(static_cast<size_t>(n));
    Box3& t = m.box;
    for (int dir = 0; dir < 6; dir++) {
        const int axis = dir / 2;
        const bool up = dir % 2 == 1;
        // reach of a box in this direction, larger = farther out
        auto reach = [&](const Box3& b) { return up ? b.hi[axis] : -b.lo[axis]; };
        for (int i = 0; i < n; i++) order[static_cast<size_t>(i)] = i;
        std::sort(order.begin(), order.end(), [&](int a, int b) {
            return reach(m.face_boxes[static_cast<size_t>(a)]) > reach(m.face_boxes[static_cast<size_t>(b)]);
        });
        for (int i : order) {
            const bool have_t = t.lo[0] <= t.hi[0];
            if (have_t && reach(m.face_boxes[static_cast<size_t>(i)]) <= reach(t)) break;
            if (done[static_cast<size_t>(i)]) continue;
            done[static_cast<size_t>(i)] = 1;
            m.optimal_boxes++;
            Bnd_Box ob;
            try {
                BRepBndLib::AddOptimal(m.faces(i + 1), ob, Standard_False, Standard_False);
            } catch (const Standard_Failure& e) {
                warn("face %d: optimal box failed (%s), using its containing box", i + 1, occt_what(e).c_str());
            }
            // AddOptimal pads by Precision::Confusion() (1e-7 mm); that is kept: it is
            // far below any tolerance derived from the diagonal.
            t.add(ob.IsVoid() ? m.face_boxes[static_cast<size_t>(i)] : to_box3(ob));
        }
    }
}

Model load_model(const char* path) {
    check_readable_file(path, "model");
    sniff_iges(path);

    // The parameters below only exist once the IGES controller is registered;
    // setting them before that silently fails.
    IGESControl_Controller::Init();
    // Lengths in millimetres whatever the file's unit (it is the default, but a
    // default is not a guarantee and the oracle's numbers must be in mm).
    set_static("xstep.cascade.unit", "MM");
    // Keep B-splines as they are in the file.  The default (1) makes the reader
    // split/convert C0 curves and surfaces to C1, which can move geometry within a
    // tolerance and change the face count; an oracle must see the file's geometry.
    set_static("read.iges.bspline.continuity", 0);
    // Tolerances of the file (read.precision.mode 0 = "File") so healing does not
    // invent coarser ones.
    set_static("read.precision.mode", 0);

    IGESControl_Reader reader;
    IFSelect_ReturnStatus st = IFSelect_RetError;
    try {
        st = reader.ReadFile(path);
    } catch (const Standard_Failure& e) {
        throw InputError(strf("OCCT failed to parse '%s': %s", path, occt_what(e).c_str()));
    }
    if (st != IFSelect_RetDone)
        throw InputError(strf("OCCT could not read '%s' as IGES (status %d)", path, static_cast<int>(st)));

    Model m;
    Handle(IGESData_IGESModel) im = reader.IGESModel();
    if (!im.IsNull()) {
        const IGESData_GlobalSection& gs = im->GlobalSection();
        m.unit_flag = gs.UnitFlag();
        if (!gs.UnitName().IsNull()) m.unit_name = gs.UnitName()->ToCString();
    }
    int nroots = reader.NbRootsForTransfer();
    if (nroots <= 0) throw InputError(strf("'%s': no transferable IGES entities", path));
    try {
        reader.TransferRoots();
        m.shape = reader.OneShape();
    } catch (const Standard_Failure& e) {
        throw InputError(strf("OCCT failed to transfer '%s': %s", path, occt_what(e).c_str()));
    }
    if (m.shape.IsNull()) throw InputError(strf("'%s': OCCT produced no shape", path));
    TopExp::MapShapes(m.shape, TopAbs_FACE, m.faces);
    if (m.faces.Extent() == 0)
        throw InputError(strf("'%s': the model has no faces (%d IGES roots transferred)", path, nroots));

    compute_boxes(m);
    m.diag = std::sqrt(sq(m.box.hi[0] - m.box.lo[0]) + sq(m.box.hi[1] - m.box.lo[1]) + sq(m.box.hi[2] - m.box.lo[2]));
    if (!(m.diag > 0) || !std::isfinite(m.diag))
        throw InputError(strf("'%s': degenerate bounding box (diagonal %g)", path, m.diag));
    return m;
}

void print_unit_note(const Model& m) {
    note("file unit: %s (IGES unit flag %d); all lengths below are millimetres",
         m.unit_name.empty() ? "?" : m.unit_name.c_str(), m.unit_flag);
}

// ---------------------------------------------------------------------------------
// Distance from a point to the trimmed faces of the model
// ---------------------------------------------------------------------------------

// Distances below this (relative to the model diagonal) count as "on the model":
// the search stops there instead of looking for an even smaller distance.  The value
// reported is still a true distance to a face, so it is within 1e-9*diag of exact.
const double kStopRel = 1e-9;

class FaceDistance {
public:
    explicit FaceDistance(const Model& m) {
        const int n = m.faces.Extent();
        faces_.resize(static_cast<size_t>(n));
        stop_ = kStopRel * m.diag;
        for (int i = 0; i < n; i++) faces_[static_cast<size_t>(i)].face = TopoDS::Face(m.faces(i + 1));
        // The containing boxes, padded by a hair for rounding in the box computation
        // (the pruning below is only exact if no face pokes out of its box).
        std::vector<Box3> boxes = m.face_boxes;
        const double pad = 1e-7 * m.diag;
        for (Box3& bx : boxes)
            for (int k = 0; k < 3; k++) {
                bx.lo[k] -= pad;
                bx.hi[k] += pad;
            }
        bvh_.build(boxes);
    }

    struct Result {
        double dist = HUGE_VAL;
        int face = 0;  // OCCT face index (1-based), 0 when nothing was found
    };

    // Exact distance from p to the union of the trimmed faces.
    //
    // Faces are visited near-first through the BVH of their boxes; a face is tried
    // only while its box is closer than the best distance so far, so faces whose box
    // contains p are always tried, and a point far from everything still finds its
    // true nearest face (this subsumes "test faces whose enlarged box contains the
    // point, else all faces").  Per face, the cheap test is an orthogonal projection on
    // the surface followed by a 2D classification of the foot point against the trim
    // loops: IN/ON means the projection distance is the distance to the face.  When the
    // foot point is outside the trim (or the projection fails), the nearest point of the
    // face is on its boundary or elsewhere; that exact case is computed with
    // BRepExtrema_DistShapeShape, but only after all cheap tests, and only if the face's
    // box is still closer than the best distance found -- usually it is not.
    Result distance(const V3& p) {
        Result res;
        double best = HUGE_VAL;
        deferred_.clear();
        bvh_.nearest(p, best, [&](int item, double lb, double& b) {
            FaceRec& r = faces_[static_cast<size_t>(item)];
            double d;
            if (project_inside(r, p, d)) {
                if (d < b) {
                    b = d;
                    res.face = item + 1;
                }
            } else {
                deferred_.push_back({item, lb});
            }
            return b <= stop_;
        });
        if (best > stop_ && !deferred_.empty()) {
            std::sort(deferred_.begin(), deferred_.end(),
                      [](const Deferred& a, const Deferred& c) { return a.lb < c.lb; });
            for (const Deferred& df : deferred_) {
                if (df.lb >= best) break;
                double d = exact(faces_[static_cast<size_t>(df.item)], p);
                if (d < best) {
                    best = d;
                    res.face = df.item + 1;
                }
            }
        }
        res.dist = best;
        return res;
    }

    long long exact_calls() const { return exact_calls_; }
    long long exact_failures() const { return exact_failures_; }

private:
    struct FaceRec {
        TopoDS_Face face;
        Handle(Geom_Surface) surf;  // surface in the face's own frame (parameter space of the pcurves)
        gp_Trsf to_local;           // world -> surface frame
        double scale = 1;           // world length = local length * scale
        std::unique_ptr<GeomAPI_ProjectPointOnSurf> proj;
        std::unique_ptr<BRepTopAdaptor_FClass2d> cls;
        // Prepared on first use: a query touches few faces, and the 2D classifier is
        // not cheap to build (27734 faces in the largest model).
        enum { kNew, kUsable, kFailed } state = kNew;  // kFailed: only the exact path works
    };
    struct Deferred {
        int item;
        double lb;
    };

    void prepare(FaceRec& r, int index) {
        r.state = FaceRec::kFailed;
        try {
            TopLoc_Location loc;
            r.surf = BRep_Tool::Surface(r.face, loc);
            if (r.surf.IsNull()) {
                warn("face %d has no surface", index);
                return;
            }
            // Work in the surface's own frame: the pcurves (and so the classifier)
            // live in the parameter space of the untransformed surface.  The point is
            // moved instead of the surface, and the distance scaled back (IGES
            // transforms may carry a scale factor).
            gp_Trsf t = loc.Transformation();
            r.scale = std::fabs(t.ScaleFactor());
            r.to_local = t.Inverted();
            double u0, u1, v0, v1;
            BRepTools::UVBounds(r.face, u0, u1, v0, v1);
            // A small margin keeps foot points that fall just on the trim boundary
            // inside the search rectangle; clamp to the surface where it is bounded.
            double su0, su1, sv0, sv1;
            r.surf->Bounds(su0, su1, sv0, sv1);
            double mu = 1e-3 * (u1 - u0), mv = 1e-3 * (v1 - v0);
            u0 -= mu; u1 += mu; v0 -= mv; v1 += mv;
            if (!r.surf->IsUPeriodic()) { u0 = std::max(u0, su0); u1 = std::min(u1, su1); }
            if (!r.surf->IsVPeriodic()) { v0 = std::max(v0, sv0); v1 = std::min(v1, sv1); }
            r.proj.reset(new GeomAPI_ProjectPointOnSurf());
            r.proj->Init(r.surf, u0, u1, v0, v1);
            r.cls.reset(new BRepTopAdaptor_FClass2d(r.face, Precision::PConfusion()));
            r.state = FaceRec::kUsable;
        } catch (const Standard_Failure& e) {
            warn("face %d: cannot prepare projection (%s); exact distance only", index,
                 occt_what(e).c_str());
        }
    }

    // Projection + classification.  True when the nearest foot point on the surface
    // lies on the trimmed face; d is then the distance to the face.
    bool project_inside(FaceRec& r, const V3& p, double& d) {
        if (r.state == FaceRec::kNew) prepare(r, static_cast<int>(&r - faces_.data()) + 1);
        if (r.state != FaceRec::kUsable) return false;
        try {
            gp_Pnt q = p.pnt().Transformed(r.to_local);
            r.proj->Perform(q);
            if (!r.proj->IsDone() || r.proj->NbPoints() == 0) return false;
            double u, v;
            r.proj->LowerDistanceParameters(u, v);
            TopAbs_State s = r.cls->Perform(gp_Pnt2d(u, v));
            if (s != TopAbs_IN && s != TopAbs_ON) return false;
            d = r.proj->LowerDistance() * r.scale;
            return std::isfinite(d);
        } catch (const Standard_Failure&) {
            return false;
        }
    }

    // Exact point-to-trimmed-face distance (interior extrema, edges and vertices).
    double exact(const FaceRec& r, const V3& p) {
        exact_calls_++;
        try {
            TopoDS_Vertex v = BRepBuilderAPI_MakeVertex(p.pnt()).Vertex();
            BRepExtrema_DistShapeShape dss(v, r.face, Extrema_ExtFlag_MIN);
            if (dss.IsDone() && dss.NbSolution() > 0) return dss.Value();
        } catch (const Standard_Failure&) {
        }
        exact_failures_++;
        return HUGE_VAL;
    }

    std::vector<FaceRec> faces_;
    Bvh bvh_;
    std::vector<Deferred> deferred_;
    double stop_ = 0;
    long long exact_calls_ = 0, exact_failures_ = 0;
};

// Keeps the k largest entries (the "worst" points).
template <class T>
class WorstK {
public:
    explicit WorstK(size_t k) : k_(k) {}
    void add(double key, const T& v) {
        if (items_.size() == k_ && key <= items_.back().first) return;
        items_.emplace_back(key, v);
        std::sort(items_.begin(), items_.end(),
                  [](const std::pair<double, T>& a, const std::pair<double, T>& b) { return a.first > b.first; });
        if (items_.size() > k_) items_.pop_back();
    }
    const std::vector<std::pair<double, T>>& items() const { return items_; }
private:
    size_t k_;
    std::vector<std::pair<double, T>> items_;
};

// ---------------------------------------------------------------------------------
// Argument parsing helpers
// ---------------------------------------------------------------------------------

// Parses a strictly positive finite number (whole string).
double parse_positive(const std::string& s, const char* what) {
    errno = 0;
    char* end = nullptr;
    double v = strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || !(v > 0))
        throw UsageError(strf("%s must be a positive number, got '%s'", what, s.c_str()));
    return v;
}

// Splits "--name value" / "--name=value" options from positional arguments.
struct Args {
    std::vector<std::string> pos;
    std::map<std::string, std::string> opt;
};
Args parse_args(int argc, char** argv, int first, const std::vector<std::string>& known) {
    Args a;
    for (int i = first; i < argc; i++) {
        std::string s = argv[i];
        if (s.size() > 2 && s.compare(0, 2, "--") == 0) {
            std::string name = s, val;
            size_t eq = s.find('=');
            if (eq != std::string::npos) {
                name = s.substr(0, eq);
                val = s.substr(eq + 1);
            } else {
                if (i + 1 >= argc) throw UsageError(strf("option %s needs a value", s.c_str()));
                val = argv[++i];
            }
            if (std::find(known.begin(), known.end(), name) == known.end())
                throw UsageError(strf("unknown option %s", name.c_str()));
            a.opt[name] = val;
        } else {
            a.pos.push_back(s);
        }
    }
    return a;
}

// ---------------------------------------------------------------------------------
// info
// ---------------------------------------------------------------------------------

int cmd_info(const Args& a) {
    if (a.pos.size() != 1) throw UsageError("info needs exactly one argument: MODEL.igs");
    double sew_rel = 1e-6;
    if (a.opt.count("--sew-rel")) sew_rel = parse_positive(a.opt.at("--sew-rel"), "--sew-rel");
    Stopwatch sw;
    Model m = load_model(a.pos[0].c_str());
    double t_read = sw.seconds();

    TopTools_IndexedMapOfShape shells, solids;
    TopExp::MapShapes(m.shape, TopAbs_SHELL, shells);
    TopExp::MapShapes(m.shape, TopAbs_SOLID, solids);

    // Sew all faces at a tight tolerance, then count edges that bound exactly one
    // face.  Seam edges appear twice in their face and are not free; degenerated
    // edges (poles) bound nothing and are skipped.
    Stopwatch sw2;
    const double sew_tol = sew_rel * m.diag;
    BRepBuilderAPI_Sewing sew(sew_tol);
    for (int i = 1; i <= m.faces.Extent(); i++) sew.Add(m.faces(i));
    long long free_edges = -1, multi_edges = -1, edges = -1;
    TopTools_IndexedMapOfShape sewn_shells;
    try {
        sew.Perform();
        TopoDS_Shape sewn = sew.SewedShape();
        TopTools_IndexedDataMapOfShapeListOfShape e2f;
        TopExp::MapShapesAndAncestors(sewn, TopAbs_EDGE, TopAbs_FACE, e2f);
        free_edges = multi_edges = edges = 0;
        for (int i = 1; i <= e2f.Extent(); i++) {
            const TopoDS_Edge& e = TopoDS::Edge(e2f.FindKey(i));
            if (BRep_Tool::Degenerated(e)) continue;
            edges++;
            int n = e2f(i).Extent();
            if (n == 1) free_edges++;
            else if (n > 2) multi_edges++;
        }
        TopExp::MapShapes(sewn, TopAbs_SHELL, sewn_shells);
    } catch (const Standard_Failure& e) {
        warn("sewing failed: %s", occt_what(e).c_str());
    }
    double t_sew = sw2.seconds();

    print_unit_note(m);
    kv("faces", static_cast<long long>(m.faces.Extent()));
    kv("shells", static_cast<long long>(shells.Extent()));
    kv("solids", static_cast<long long>(solids.Extent()));
    fprintf(g_out, "bbox %.10g %.10g %.10g %.10g %.10g %.10g\n", m.box.lo[0], m.box.lo[1], m.box.lo[2],
            m.box.hi[0], m.box.hi[1], m.box.hi[2]);
    kv("diag", m.diag);
    kv("sew_tol", sew_tol);
    if (free_edges < 0) {
        note("sewing failed; free_edges unknown");
        return 1;
    }
    kv("edges", edges);
    kv("free_edges", free_edges);
    kv("multiple_edges", multi_edges);
    kv("sewn_shells", static_cast<long long>(sewn_shells.Extent()));
    note("tight box from %d optimal face boxes; time: read %.2f s, sew %.2f s", m.optimal_boxes, t_read, t_sew);
    return 0;
}

// ---------------------------------------------------------------------------------
// points
// ---------------------------------------------------------------------------------

struct InPoint {
    V3 p;
    long long id;
};

// Reads "x y z face_id" lines; '#' starts a comment line, blank lines are skipped.
// Anything else is an error that names the line.
std::vector<InPoint> read_points(const char* path) {
    check_readable_file(path, "points file");
    std::ifstream in(path);
    if (!in) throw InputError(strf("cannot open points file '%s'", path));
    std::vector<InPoint> pts;
    std::string line;
    long long lineno = 0;
    while (std::getline(in, line)) {
        lineno++;
        size_t b = line.find_first_not_of(" \t\r");
        if (b == std::string::npos || line[b] == '#') continue;
        const char* s = line.c_str() + b;
        double c[3];
        char* end = nullptr;
        bool ok = true;
        for (int k = 0; k < 3 && ok; k++) {
            errno = 0;
            c[k] = strtod(s, &end);
            if (end == s || errno == ERANGE || !std::isfinite(c[k])) ok = false;
            s = end;
        }
        long long id = 0;
        if (ok) {
            errno = 0;
            id = strtoll(s, &end, 10);
            if (end == s || errno == ERANGE || (*end != '\0' && !isspace(static_cast<unsigned char>(*end))))
                ok = false;
            s = end;
        }
        if (ok) {
            while (*s && isspace(static_cast<unsigned char>(*s))) s++;
            if (*s != '\0') ok = false;
        }
        if (!ok) {
            std::string shown = line.substr(0, 80);
            if (!shown.empty() && shown.back() == '\r') shown.pop_back();
            throw InputError(strf("%s:%lld: expected 'x y z face_id' (3 finite numbers and an integer), got '%s'",
                                  path, lineno, shown.c_str()));
        }
        pts.push_back({V3(c[0], c[1], c[2]), id});
    }
    if (in.bad()) throw InputError(strf("error reading '%s'", path));
    if (pts.empty()) throw InputError(strf("'%s' contains no points", path));
    return pts;
}

int cmd_points(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("points needs MODEL.igs POINTS.xyz");
    double tol_rel = 1e-6;
    if (a.opt.count("--tol-rel")) tol_rel = parse_positive(a.opt.at("--tol-rel"), "--tol-rel");
    std::vector<InPoint> pts = read_points(a.pos[1].c_str());  // cheap: fail early on bad input
    FILE* dump = nullptr;
    if (a.opt.count("--out")) {
        dump = fopen(a.opt.at("--out").c_str(), "w");
        if (!dump) throw InputError(strf("cannot write '%s': %s", a.opt.at("--out").c_str(), strerror(errno)));
        fprintf(dump, "# x y z face_id distance nearest_occt_face\n");
    }
    Stopwatch sw;
    Model m = load_model(a.pos[0].c_str());
    double t_read = sw.seconds();
    const double tol = tol_rel * m.diag;

    Stopwatch sw2;
    FaceDistance fd(m);
    double t_prep = sw2.seconds();

    Stopwatch sw3;
    struct PerFace { double max = 0; long long over = 0; };
    std::map<long long, PerFace> per_face;
    WorstK<InPoint> worst(10);
    double maxd = 0, sum = 0;
    long long over = 0, unresolved = 0;
    for (const InPoint& ip : pts) {
        FaceDistance::Result r = fd.distance(ip.p);
        double d = r.dist;
        if (dump)
            fprintf(dump, "%.17g %.17g %.17g %lld %.10g %d\n", ip.p.x, ip.p.y, ip.p.z, ip.id, d, r.face);
        if (!std::isfinite(d)) unresolved++;
        if (d > tol) {
            over++;
            PerFace& pf = per_face[ip.id];
            pf.max = std::max(pf.max, d);
            pf.over++;
        }
        maxd = std::max(maxd, d);
        sum += d;
        worst.add(d, ip);
    }
    double t_query = sw3.seconds();
    if (dump && fclose(dump) != 0) throw InputError(strf("error writing '%s'", a.opt.at("--out").c_str()));

    print_unit_note(m);
    kv("points", static_cast<long long>(pts.size()));
    kv("tol", tol);
    kv("max_dist", maxd);
    kv("mean_dist", sum / static_cast<double>(pts.size()));
    kv("over_tol", over);
    for (const auto& f : per_face)
        fprintf(g_out, "face %lld max %.10g count %lld\n", f.first, f.second.max, f.second.over);
    for (const auto& w : worst.items())
        note("worst: %.10g %.10g %.10g %lld %.10g", w.second.p.x, w.second.p.y, w.second.p.z, w.second.id, w.first);
    if (unresolved) note("%lld points: OCCT found no distance (reported as inf)", unresolved);
    note("diag %.10g mm, %d OCCT faces; exact boundary distances %lld (%lld failed)", m.diag,
         m.faces.Extent(), fd.exact_calls(), fd.exact_failures());
    note("time: read %.2f s, prepare %.2f s, %zu queries %.2f s", t_read, t_prep, pts.size(), t_query);
    return over > 0 ? 1 : 0;
}

// ---------------------------------------------------------------------------------
// STL reading / writing
// ---------------------------------------------------------------------------------

struct Tri {
    V3 a, b, c;
};

uint32_t le32(const unsigned char* p) {
    return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
           (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
float lef32(const unsigned char* p) {
    uint32_t u = le32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

// Binary STL is recognised by its exact size (84 + 50*n); many binary files start with
// "solid" in the header, so the keyword alone does not mean ASCII.
std::vector<Tri> read_stl(const char* path) {
    check_readable_file(path, "mesh");
    std::ifstream in(path, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw InputError(strf("error reading '%s'", path));
    std::vector<Tri> tris;
    if (data.size() >= 84) {
        const unsigned char* u = reinterpret_cast<const unsigned char*>(data.data());
        uint32_t n = le32(u + 80);
        if (84 + 50ull * n == data.size()) {
            tris.reserve(n);
            for (uint32_t i = 0; i < n; i++) {
                const unsigned char* t = u + 84 + 50ull * i + 12;  // skip the normal
                Tri tr;
                V3* v[3] = {&tr.a, &tr.b, &tr.c};
                for (int k = 0; k < 3; k++)
                    *v[k] = V3(lef32(t + 12 * k), lef32(t + 12 * k + 4), lef32(t + 12 * k + 8));
                tris.push_back(tr);
            }
            for (size_t i = 0; i < tris.size(); i++) {
                const Tri& t = tris[i];
                for (const V3* p : {&t.a, &t.b, &t.c})
                    if (!std::isfinite(p->x) || !std::isfinite(p->y) || !std::isfinite(p->z))
                        throw InputError(strf("%s: triangle %zu has a non-finite coordinate", path, i + 1));
            }
            if (tris.empty()) throw InputError(strf("'%s' has no triangles", path));
            return tris;
        }
    }
    // ASCII: "vertex x y z" lines, three per facet.
    size_t b = data.find_first_not_of(" \t\r\n");
    if (b == std::string::npos || data.compare(b, 5, "solid") != 0)
        throw InputError(strf("'%s' is neither binary STL (size is not 84+50*n) nor ASCII STL (no 'solid')", path));
    std::vector<V3> verts;
    size_t pos = 0;
    long long lineno = 0;
    while (pos < data.size()) {
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos) eol = data.size();
        std::string line = data.substr(pos, eol - pos);
        pos = eol + 1;
        lineno++;
        size_t s = line.find_first_not_of(" \t\r");
        if (s == std::string::npos || line.compare(s, 6, "vertex") != 0) continue;
        const char* c = line.c_str() + s + 6;
        double x[3];
        for (int k = 0; k < 3; k++) {
            char* end = nullptr;
            errno = 0;
            x[k] = strtod(c, &end);
            if (end == c || errno == ERANGE || !std::isfinite(x[k]))
                throw InputError(strf("%s:%lld: malformed vertex line", path, lineno));
            c = end;
        }
        verts.emplace_back(x[0], x[1], x[2]);
    }
    if (verts.size() % 3 != 0)
        throw InputError(strf("'%s': %zu vertex lines, not a multiple of 3", path, verts.size()));
    for (size_t i = 0; i + 2 < verts.size(); i += 3) tris.push_back({verts[i], verts[i + 1], verts[i + 2]});
    if (tris.empty()) throw InputError(strf("'%s' has no triangles", path));
    return tris;
}

// Distance from p to triangle (a,b,c): the foot point on the plane if it falls inside
// the triangle, else the nearest point of the three edges.  Degenerate triangles
// (zero area) reduce to their edges.
double seg_dist(const V3& p, const V3& a, const V3& b) {
    V3 ab = b - a;
    double l2 = dot(ab, ab);
    double t = l2 > 0 ? dot(p - a, ab) / l2 : 0;
    t = std::min(1.0, std::max(0.0, t));
    return norm(p - (a + t * ab));
}
double tri_dist(const V3& p, const Tri& t) {
    V3 e0 = t.b - t.a, e1 = t.c - t.a;
    V3 n = cross(e0, e1);
    double n2 = dot(n, n);
    if (n2 > 0) {
        V3 ap = p - t.a;
        // barycentric coordinates of the plane foot point from the sub-triangle areas
        double wb = dot(cross(ap, e1), n) / n2;
        double wc = dot(cross(e0, ap), n) / n2;
        if (wb >= 0 && wc >= 0 && wb + wc <= 1) return std::fabs(dot(ap, n)) / std::sqrt(n2);
    }
    return std::min(seg_dist(p, t.a, t.b), std::min(seg_dist(p, t.b, t.c), seg_dist(p, t.c, t.a)));
}

class TriMesh {
public:
    explicit TriMesh(std::vector<Tri> tris) : tris_(std::move(tris)) {
        std::vector<Box3> boxes(tris_.size());
        for (size_t i = 0; i < tris_.size(); i++) {
            boxes[i].add(tris_[i].a);
            boxes[i].add(tris_[i].b);
            boxes[i].add(tris_[i].c);
        }
        bvh_.build(boxes);
    }
    double distance(const V3& p) const {
        double best = HUGE_VAL;
        bvh_.nearest(p, best, [&](int item, double, double& b) {
            double d = tri_dist(p, tris_[static_cast<size_t>(item)]);
            if (d < b) b = d;
            return false;
        });
        return best;
    }
    const std::vector<Tri>& tris() const { return tris_; }
private:
    std::vector<Tri> tris_;
    Bvh bvh_;
};

// Meshes the model with OCCT.  Linear deflection is absolute (defl_rel * diag).
void mesh_model(const Model& m, double defl) {
    BRepMesh_IncrementalMesh mesher(m.shape, defl, Standard_False, 0.5, Standard_True);
    if (!mesher.IsDone()) warn("BRepMesh_IncrementalMesh reported not done");
}

// A point of the OCCT tessellation, in world coordinates, with its face.
struct ModelSample {
    V3 p;
    int face;
};

// Tessellation vertices, plus one point per triangle.  The per-triangle point is the
// triangle's UV centroid mapped through the surface, so it lies ON the model (the 3D
// centroid would be off the surface by up to the deflection, and that sag would be
// blamed on MESH).  Faces without UV nodes fall back to the 3D centroid.
std::vector<ModelSample> model_samples(const Model& m, long long& faces_without_mesh) {
    std::vector<ModelSample> out;
    faces_without_mesh = 0;
    for (int i = 1; i <= m.faces.Extent(); i++) {
        const TopoDS_Face& f = TopoDS::Face(m.faces(i));
        TopLoc_Location loc;
        Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(f, loc);
        if (tri.IsNull() || tri->NbTriangles() == 0) {
            faces_without_mesh++;
            continue;
        }
        gp_Trsf t = loc.Transformation();
        for (int k = 1; k <= tri->NbNodes(); k++) out.push_back({V3(tri->Node(k).Transformed(t)), i});
        TopLoc_Location sloc;
        Handle(Geom_Surface) s = BRep_Tool::Surface(f, sloc);
        gp_Trsf st = sloc.Transformation();
        for (int k = 1; k <= tri->NbTriangles(); k++) {
            int n1, n2, n3;
            tri->Triangle(k).Get(n1, n2, n3);
            gp_Pnt c;
            bool done = false;
            if (tri->HasUVNodes() && !s.IsNull()) {
                gp_XY uv = (tri->UVNode(n1).XY() + tri->UVNode(n2).XY() + tri->UVNode(n3).XY()) / 3.0;
                try {
                    c = s->Value(uv.X(), uv.Y()).Transformed(st);
                    done = true;
                } catch (const Standard_Failure&) {
                }
            }
            if (!done) c = gp_Pnt((tri->Node(n1).XYZ() + tri->Node(n2).XYZ() + tri->Node(n3).XYZ()) / 3.0).Transformed(t);
            out.push_back({V3(c), i});
        }
    }
    return out;
}

// ---------------------------------------------------------------------------------
// mesh-dev
// ---------------------------------------------------------------------------------

int cmd_mesh_dev(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("mesh-dev needs MODEL.igs MESH.stl");
    double defl_rel = 1e-4;
    if (a.opt.count("--defl-rel")) defl_rel = parse_positive(a.opt.at("--defl-rel"), "--defl-rel");
    Stopwatch sw;
    TriMesh mesh(read_stl(a.pos[1].c_str()));
    Model m = load_model(a.pos[0].c_str());
    double t_read = sw.seconds();

    // (a) mesh -> model: unique mesh vertices (STL repeats them per triangle) and
    // triangle centroids.
    Stopwatch sw2;
    std::vector<V3> q;
    for (const Tri& t : mesh.tris()) {
        q.push_back(t.a);
        q.push_back(t.b);
        q.push_back(t.c);
    }
    auto lt = [](const V3& u, const V3& v) {
        return u.x != v.x ? u.x < v.x : (u.y != v.y ? u.y < v.y : u.z < v.z);
    };
    auto eq = [](const V3& u, const V3& v) { return u.x == v.x && u.y == v.y && u.z == v.z; };
    std::sort(q.begin(), q.end(), lt);
    q.erase(std::unique(q.begin(), q.end(), eq), q.end());
    const size_t nverts = q.size();
    for (const Tri& t : mesh.tris()) q.push_back((1.0 / 3.0) * (t.a + t.b + t.c));

    FaceDistance fd(m);
    WorstK<V3> worst_a(10);
    double max_a = 0, sum_a = 0;
    long long unresolved = 0;
    for (const V3& p : q) {
        double d = fd.distance(p).dist;
        if (!std::isfinite(d)) unresolved++;
        max_a = std::max(max_a, d);
        sum_a += d;
        worst_a.add(d, p);
    }
    double t_a = sw2.seconds();

    // (b) model -> mesh
    Stopwatch sw3;
    const double defl = defl_rel * m.diag;
    mesh_model(m, defl);
    long long unmeshed = 0;
    std::vector<ModelSample> ms = model_samples(m, unmeshed);
    WorstK<ModelSample> worst_b(10);
    double max_b = 0, sum_b = 0;
    for (const ModelSample& s : ms) {
        double d = mesh.distance(s.p);
        max_b = std::max(max_b, d);
        sum_b += d;
        worst_b.add(d, s);
    }
    double t_b = sw3.seconds();

    print_unit_note(m);
    kv("diag", m.diag);
    kv("mesh_triangles", static_cast<long long>(mesh.tris().size()));
    kv("mesh_vertices", static_cast<long long>(nverts));
    kv("mesh_to_model_points", static_cast<long long>(q.size()));
    kv("mesh_to_model_max", max_a);
    kv("mesh_to_model_mean", q.empty() ? 0.0 : sum_a / static_cast<double>(q.size()));
    kv("model_defl", defl);
    kv("model_to_mesh_points", static_cast<long long>(ms.size()));
    kv("model_to_mesh_max", max_b);
    kv("model_to_mesh_mean", ms.empty() ? 0.0 : sum_b / static_cast<double>(ms.size()));
    for (const auto& w : worst_a.items())
        note("worst mesh_to_model: %.10g %.10g %.10g %.10g", w.second.x, w.second.y, w.second.z, w.first);
    for (const auto& w : worst_b.items())
        note("worst model_to_mesh: %.10g %.10g %.10g occt_face %d %.10g", w.second.p.x, w.second.p.y,
             w.second.p.z, w.second.face, w.first);
    if (unresolved) note("%lld mesh points: OCCT found no distance (reported as inf)", unresolved);
    if (unmeshed) note("%lld faces got no OCCT triangulation (not sampled for model_to_mesh)", unmeshed);
    note("time: read %.2f s, mesh->model %.2f s (%lld exact boundary distances), model->mesh %.2f s", t_read, t_a,
         fd.exact_calls(), t_b);
    return 0;
}

// ---------------------------------------------------------------------------------
// sample
// ---------------------------------------------------------------------------------

int cmd_sample(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("sample needs MODEL.igs OUT.xyz");
    long long per_face = 20;
    if (a.opt.count("--per-face")) {
        const std::string& s = a.opt.at("--per-face");
        char* end = nullptr;
        errno = 0;
        per_face = strtoll(s.c_str(), &end, 10);
        if (s.empty() || *end || errno || per_face < 1 || per_face > 1000000)
            throw UsageError(strf("--per-face must be an integer in 1..1000000, got '%s'", s.c_str()));
    }
    Model m = load_model(a.pos[0].c_str());
    FILE* out = fopen(a.pos[1].c_str(), "w");
    if (!out) throw InputError(strf("cannot write '%s': %s", a.pos[1].c_str(), strerror(errno)));
    fprintf(out, "# occt_oracle sample of %s: x y z occt_face_index (mm)\n", a.pos[0].c_str());

    // Fixed seed: the same model gives the same file.
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    long long total = 0, short_faces = 0;
    for (int i = 1; i <= m.faces.Extent(); i++) {
        const TopoDS_Face& f = TopoDS::Face(m.faces(i));
        long long got = 0;
        try {
            TopLoc_Location loc;
            Handle(Geom_Surface) s = BRep_Tool::Surface(f, loc);
            if (s.IsNull()) throw Standard_Failure("face has no surface");
            gp_Trsf t = loc.Transformation();
            double u0, u1, v0, v1;
            BRepTools::UVBounds(f, u0, u1, v0, v1);
            BRepTopAdaptor_FClass2d cls(f, Precision::PConfusion());
            // Jittered grid over the UV box, cells in random order so that a face that
            // fills only part of its box still gets spread-out points; strictly IN
            // points only (ON points sit on a trim curve, ambiguous by nature).
            // The grid has ~4x more cells than points wanted, and a second, denser
            // round catches thin faces.
            for (int round = 0; round < 2 && got < per_face; round++) {
                long long cells = per_face * (round == 0 ? 4 : 64);
                int g = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(cells)))));
                std::vector<int> idx(static_cast<size_t>(g) * static_cast<size_t>(g));
                for (size_t k = 0; k < idx.size(); k++) idx[k] = static_cast<int>(k);
                std::shuffle(idx.begin(), idx.end(), rng);
                for (int k : idx) {
                    if (got >= per_face) break;
                    double u = u0 + (u1 - u0) * ((k % g) + U(rng)) / g;
                    double v = v0 + (v1 - v0) * ((k / g) + U(rng)) / g;
                    if (cls.Perform(gp_Pnt2d(u, v)) != TopAbs_IN) continue;
                    gp_Pnt p = s->Value(u, v).Transformed(t);
                    if (!std::isfinite(p.X()) || !std::isfinite(p.Y()) || !std::isfinite(p.Z())) continue;
                    fprintf(out, "%.17g %.17g %.17g %d\n", p.X(), p.Y(), p.Z(), i);
                    got++;
                }
            }
        } catch (const Standard_Failure& e) {
            warn("face %d: sampling failed: %s", i, occt_what(e).c_str());
        }
        if (got < per_face) {
            short_faces++;
            note("face %d: only %lld of %lld points inside the trim", i, got, per_face);
        }
        total += got;
    }
    if (fclose(out) != 0) throw InputError(strf("error writing '%s'", a.pos[1].c_str()));
    print_unit_note(m);
    kv("faces", static_cast<long long>(m.faces.Extent()));
    kv("points", total);
    kv("short_faces", short_faces);
    kv("diag", m.diag);
    return 0;
}

// ---------------------------------------------------------------------------------
// write-stl (hidden; makes test meshes)
// ---------------------------------------------------------------------------------

int cmd_write_stl(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("write-stl needs MODEL.igs OUT.stl");
    double defl_rel = 1e-4;
    if (a.opt.count("--defl-rel")) defl_rel = parse_positive(a.opt.at("--defl-rel"), "--defl-rel");
    Model m = load_model(a.pos[0].c_str());
    mesh_model(m, defl_rel * m.diag);

    std::vector<float> rec;  // 12 floats per triangle: normal, 3 vertices
    for (int i = 1; i <= m.faces.Extent(); i++) {
        const TopoDS_Face& f = TopoDS::Face(m.faces(i));
        TopLoc_Location loc;
        Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(f, loc);
        if (tri.IsNull()) continue;
        gp_Trsf t = loc.Transformation();
        // reversed faces: swap two vertices so the STL normal points out of the material
        bool rev = f.Orientation() == TopAbs_REVERSED;
        for (int k = 1; k <= tri->NbTriangles(); k++) {
            int n[3];
            tri->Triangle(k).Get(n[0], n[1], n[2]);
            if (rev) std::swap(n[1], n[2]);
            V3 p[3];
            for (int j = 0; j < 3; j++) p[j] = V3(tri->Node(n[j]).Transformed(t));
            V3 nn = cross(p[1] - p[0], p[2] - p[0]);
            double l = norm(nn);
            if (l > 0) nn = (1.0 / l) * nn;
            rec.push_back(static_cast<float>(nn.x));
            rec.push_back(static_cast<float>(nn.y));
            rec.push_back(static_cast<float>(nn.z));
            for (int j = 0; j < 3; j++) {
                rec.push_back(static_cast<float>(p[j].x));
                rec.push_back(static_cast<float>(p[j].y));
                rec.push_back(static_cast<float>(p[j].z));
            }
        }
    }
    const size_t ntri = rec.size() / 12;
    if (ntri == 0) throw InputError("OCCT produced no triangles");
    if (ntri > 0xffffffffu) throw InputError("too many triangles for binary STL");
    FILE* out = fopen(a.pos[1].c_str(), "wb");
    if (!out) throw InputError(strf("cannot write '%s': %s", a.pos[1].c_str(), strerror(errno)));
    unsigned char hdr[84] = {0};
    snprintf(reinterpret_cast<char*>(hdr), 80, "occt_oracle write-stl defl-rel %g", defl_rel);
    uint32_t n32 = static_cast<uint32_t>(ntri);
    for (int k = 0; k < 4; k++) hdr[80 + k] = static_cast<unsigned char>(n32 >> (8 * k));
    bool ok = fwrite(hdr, 1, 84, out) == 84;
    static_assert(sizeof(float) == 4, "binary STL needs 32-bit floats");
    for (size_t i = 0; i < ntri && ok; i++) {
        unsigned char buf[50] = {0};
        for (int k = 0; k < 12; k++) {
            uint32_t u;
            memcpy(&u, &rec[12 * i + static_cast<size_t>(k)], 4);
            for (int j = 0; j < 4; j++) buf[4 * k + j] = static_cast<unsigned char>(u >> (8 * j));
        }
        ok = fwrite(buf, 1, 50, out) == 50;
    }
    if (fclose(out) != 0 || !ok) throw InputError(strf("error writing '%s'", a.pos[1].c_str()));
    kv("triangles", static_cast<long long>(ntri));
    kv("defl", defl_rel * m.diag);
    kv("diag", m.diag);
    return 0;
}

// ---------------------------------------------------------------------------------
// main
// ---------------------------------------------------------------------------------

const char* kUsage =
    "usage: occt_oracle [-v] COMMAND ARGS\n"
    "  info     MODEL.igs [--sew-rel R]            faces, shells, solids, bbox, diag, free_edges\n"
    "                                               (faces sewn at R*diag, default 1e-6)\n"
    "  points   MODEL.igs POINTS.xyz [--tol-rel R]  distance of 'x y z face_id' points to the faces\n"
    "                    [--out FILE]               (default R 1e-6; exit 1 if any point > R*diag;\n"
    "                                               FILE gets every point's distance and nearest face)\n"
    "  mesh-dev MODEL.igs MESH.stl [--defl-rel R]   two-sided deviation mesh <-> model\n"
    "                                               (model tessellated at R*diag, default 1e-4)\n"
    "  sample   MODEL.igs OUT.xyz [--per-face N]    N points (default 20) inside every face\n"
    "Output: 'key value' lines on stdout, '# ' lines for people; lengths in mm.\n"
    "Exit: 0 ok, 1 check failed, 2 usage or input error.  -v shows OCCT's own messages.\n";

// Quiet by default: OCCT's reader prints load/transfer reports that nobody reads in
// a test log.  Failures are still printed (to stderr, see main).
void configure_messages() {
    const Handle(Message_Messenger)& msgr = Message::DefaultMessenger();
    for (Message_SequenceOfPrinters::Iterator it(msgr->Printers()); it.More(); it.Next())
        it.Value()->SetTraceLevel(g_verbose ? Message_Trace : Message_Fail);
}

int run(int argc, char** argv) {
    int first = 1;
    while (first < argc && (strcmp(argv[first], "-v") == 0 || strcmp(argv[first], "--verbose") == 0)) {
        g_verbose = true;
        first++;
    }
    if (first < argc && (strcmp(argv[first], "-h") == 0 || strcmp(argv[first], "--help") == 0)) {
        fputs(kUsage, g_out);
        return 0;
    }
    if (first >= argc) throw UsageError("no command");
    configure_messages();
    std::string cmd = argv[first];
    if (cmd == "info") return cmd_info(parse_args(argc, argv, first + 1, {"--sew-rel"}));
    if (cmd == "points") return cmd_points(parse_args(argc, argv, first + 1, {"--tol-rel", "--out"}));
    if (cmd == "mesh-dev") return cmd_mesh_dev(parse_args(argc, argv, first + 1, {"--defl-rel"}));
    if (cmd == "sample") return cmd_sample(parse_args(argc, argv, first + 1, {"--per-face"}));
    if (cmd == "write-stl") return cmd_write_stl(parse_args(argc, argv, first + 1, {"--defl-rel"}));
    throw UsageError(strf("unknown command '%s'", cmd.c_str()));
}

}  // namespace

int main(int argc, char** argv) {
    // Keep stdout for our results only: OCCT writes reports to std::cout / fd 1.
    fflush(stdout);
    int fd = dup(STDOUT_FILENO);
    if (fd >= 0) {
        FILE* f = fdopen(fd, "w");
        if (f && dup2(STDERR_FILENO, STDOUT_FILENO) >= 0) g_out = f;
    }
    int rc;
    try {
        rc = run(argc, argv);
    } catch (const UsageError& e) {
        fprintf(stderr, "occt_oracle: %s\n%s", e.what(), kUsage);
        rc = 2;
    } catch (const InputError& e) {
        fprintf(stderr, "occt_oracle: %s\n", e.what());
        rc = 2;
    } catch (const Standard_Failure& e) {
        fprintf(stderr, "occt_oracle: OCCT exception: %s\n", occt_what(e).c_str());
        rc = 2;
    } catch (const std::exception& e) {
        fprintf(stderr, "occt_oracle: %s\n", e.what());
        rc = 2;
    }
    if (fflush(g_out) != 0) {
        fprintf(stderr, "occt_oracle: cannot write results to stdout\n");
        rc = 2;
    }
    return rc;
}

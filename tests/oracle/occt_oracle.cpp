// occt_oracle - an independent test oracle for curvemesh, built on Open CASCADE (OCCT).
//
// curvemesh rebuilds every face of a CAD model from its boundary curves.  To judge
// that result we need answers that do not come from curvemesh's own IGES/STEP readers
// or geometry kernels: what the model contains, how far a set of points is from the
// real (trimmed) faces, and how far a decoded triangle mesh is from the model in both
// directions.  This tool gives those answers using OCCT only.
//
//   occt_oracle info      MODEL [--sew-rel 1e-6]
//   occt_oracle points    MODEL POINTS.xyz [--tol-rel 1e-6] [--out FILE]
//   occt_oracle mesh-dev  MODEL MESH.stl   [--defl-rel 1e-4] [--max-points N] [--per-face-out F]
//   occt_oracle sample    MODEL OUT.xyz    [--per-face 20]
//   occt_oracle write-stl MODEL OUT.stl    [--defl-rel 1e-4] [--angle 0.5]   (hidden: test and bench meshes)
//   every command: [--curves file|3d]   (which trim curves define the faces)
//
// MODEL is an IGES file or a STEP file (ISO 10303-21, any AP that OCCT's
// STEPControl_Reader reads), told apart by content, not by name: a STEP file starts
// with "ISO-10303-21" (after blanks and a UTF-8 BOM), everything else must be
// fixed-format IGES.  Both come out in millimetres.
//
// Output: machine-readable "key value" lines on stdout, human-readable lines start
// with "# ".  Exit status: 0 success, 1 a check failed (points farther than tol),
// 2 usage or input error.  Diagnostics go to stderr.  OCCT itself prints to stdout in
// places (IGES/STEP load reports, messenger), so fd 1 is redirected to stderr at
// start-up and our own results go to a private duplicate of the original stdout.
//
// See tests/oracle/README.md for the method and the OCCT pitfalls met.

#include <Bnd_Box.hxx>
#include <BndLib_AddSurface.hxx>
#include <BRep_Tool.hxx>
#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <Extrema_ExtPElS.hxx>
#include <Extrema_ExtPS.hxx>
#include <Extrema_GenExtPS.hxx>
#include <Extrema_POnSurf.hxx>
#include <BndLib_Add3dCurve.hxx>
#include <Geom_BezierCurve.hxx>
#include <Geom_BezierSurface.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <GeomAPI_ProjectPointOnCurve.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Trsf.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Poly_PolygonOnTriangulation.hxx>
#include <Poly_Triangulation.hxx>
#include <Precision.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
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
bool g_curves_3d = false;  // --curves 3d: trim curves from the 3D curves (see load_model)

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
inline double sq(double x) { return x * x; }

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
    double diag() const { return std::sqrt(sq(hi[0] - lo[0]) + sq(hi[1] - lo[1]) + sq(hi[2] - lo[2])); }
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
    const char* format = "IGES";       // "IGES" or "STEP": which reader made `shape`
    std::string unit_name;             // the file's length unit(s), as the file names them
    int unit_flag = 0;                 // IGES only: global-section unit flag
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
// Compressed ('C') and binary ('B') IGES are not supported by OCCT either.  Called
// once sniff_step has said the file is not STEP, so the message says both.
void sniff_iges(const char* path) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line.empty())
        throw InputError(strf("'%s' is empty or starts with an empty line, not an IGES or STEP file", path));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.size() < 73 || (line[72] != 'S' && line[72] != 'G'))
        throw InputError(strf("'%s' is neither a STEP file (it does not start with 'ISO-10303-21') nor a "
                              "fixed-format IGES file (line 1 has no 'S' or 'G' section letter in column 73)",
                              path));
}

// Which reader a model needs, told by content: file names lie (.stp, .step, .p21,
// .igs, .iges, or none).  An ISO 10303-21 exchange structure begins with the keyword
// "ISO-10303-21;" (ISO 10303-21 clause 5.1); some writers put blanks or a UTF-8 BOM
// before it.  Everything else is taken to be IGES and checked by sniff_iges.
// Returns true for STEP, with `skip` = bytes of BOM to skip before handing the file
// to OCCT: OCCT 7.6's STEP lexer does not know the BOM (syntax error "unexpected QUID"
// on the cube with a BOM, then a crash if the reader is used further), while leading
// blanks are fine and are kept so that OCCT's line numbers stay those of the file.
bool sniff_step(const char* path, std::streamoff& skip) {
    std::ifstream in(path, std::ios::binary);
    skip = 0;
    unsigned char bom[3] = {0, 0, 0};
    in.read(reinterpret_cast<char*>(bom), 3);
    if (in.gcount() == 3 && bom[0] == 0xEF && bom[1] == 0xBB && bom[2] == 0xBF) skip = 3;
    in.clear();
    in.seekg(skip);
    int c;
    long blanks = 0;
    while ((c = in.get()) != EOF && (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'))
        blanks++;
    if (c == EOF) {
        if (skip > 0 || blanks > 0)
            throw InputError(strf("'%s' has nothing but blanks, not an IGES or STEP file", path));
        return false;  // empty: sniff_iges says so
    }
    static const char kKey[] = "ISO-10303-21";
    char buf[sizeof kKey - 1];
    buf[0] = static_cast<char>(c);
    in.read(buf + 1, sizeof buf - 1);
    return in.gcount() == static_cast<std::streamsize>(sizeof buf - 1) && memcmp(buf, kKey, sizeof buf) == 0;
}

void set_static(const char* name, const char* value) {
    if (!Interface_Static::SetCVal(name, value))
        warn("could not set OCCT parameter %s=%s", name, value);
}
void set_static(const char* name, int value) {
    if (!Interface_Static::SetIVal(name, value))
        warn("could not set OCCT parameter %s=%d", name, value);
}

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

// What an XSControl_Reader::ReadFile/ReadStream status means, for error messages
// (IFSelect_WorkSession::ReadFile: RetError when the file cannot be opened or is not
// recognised, RetFail when the parser hit errors; the parser's own report goes through
// the messenger, which prints failures to stderr).
const char* read_status_text(IFSelect_ReturnStatus st) {
    switch (st) {
    case IFSelect_RetVoid: return "nothing was read";
    case IFSelect_RetError: return "the file could not be opened or recognised";
    case IFSelect_RetFail: return "the parser failed; OCCT's messages above say where";
    case IFSelect_RetStop: return "reading was stopped";
    default: return "unknown status";
    }
}

// Parameters common to both readers.  They only exist once a controller (IGES or STEP)
// is registered; setting them before that silently fails.
void set_xstep_statics(int surfacecurve_mode) {
    // Lengths in millimetres whatever the file's unit (it is the default, but a
    // default is not a guarantee and the oracle's numbers must be in mm).  Both
    // readers honour it: "M" really scales IGES and STEP results by 1e-3.
    set_static("xstep.cascade.unit", "MM");
    // Tolerances of the file (read.precision.mode 0 = "File": IGES global section,
    // STEP uncertainty_measure_with_unit) so healing does not invent coarser ones.
    set_static("read.precision.mode", 0);
    // Trim curves: which of an edge's 3D curve and parameter-space curve(s) build the
    // face; the values differ between IGES and STEP (see the two readers).
    set_static("read.surfacecurve.mode", surfacecurve_mode);
}

// IGES: fills m.shape and the unit fields; returns the number of roots transferred.
int read_iges(const char* path, Model& m) {
    IGESControl_Controller::Init();
    // Trim curves: an IGES 142 curve-on-surface may carry both a parameter-space
    // curve and a 3D curve, with a preference flag.  By default (mode 0) OCCT follows
    // the flag, as the standard says.  Some exporters' two curves disagree badly
    // (SolidWorks, PREF=1 "2D preferred": up to 0.57 mm on the 20 mm hex nut), which
    // shows as large edge tolerances (info: max_tol); --curves 3d (mode -3) rebuilds
    // every parameter-space curve from the 3D one instead, to cross-check.
    set_xstep_statics(g_curves_3d ? -3 : 0);
    // Keep B-splines as they are in the file.  The default (1) makes the reader
    // split/convert C0 curves and surfaces to C1, which can move geometry within a
    // tolerance and change the face count; an oracle must see the file's geometry.
    set_static("read.iges.bspline.continuity", 0);
    // blanked (hidden) entities are not part of the model a CAD system shows, and cmz leaves them
    // out by default (iges_brep.c); so does OCCT with this (ovt__asmo's six blanked planes,
    // Shelt_channel_5's 30 blanked subfigure instances: 3358 faces each, both ways compared)
    set_static("read.iges.onlyvisible", 1);

    IGESControl_Reader reader;
    IFSelect_ReturnStatus st = IFSelect_RetError;
    try {
        st = reader.ReadFile(path);
    } catch (const Standard_Failure& e) {
        throw InputError(strf("OCCT failed to parse '%s' as IGES: %s", path, occt_what(e).c_str()));
    }
    if (st != IFSelect_RetDone)
        throw InputError(strf("OCCT could not read '%s' as IGES (status %d: %s)", path, static_cast<int>(st),
                              read_status_text(st)));

    m.format = "IGES";
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
    return nroots;
}

// STEP: fills m.shape and m.unit_name; returns the number of roots transferred.
// `skip` is the UTF-8 BOM to step over (see sniff_step).
int read_step(const char* path, std::streamoff skip, Model& m) {
    STEPControl_Controller::Init();
    // Trim curves: a STEP edge always has its 3D curve (edge_curve); a surface_curve
    // may add pcurves on the faces' surfaces.  Mode 0 (default) uses those pcurves
    // where the file gives them and computes the others from the 3D curve.  For
    // --curves 3d the STEP value is +3: StepToTopoDS_TranslateEdgeLoop then ignores
    // the file's pcurves and rebuilds every one from the 3D curve.  (-3, the IGES
    // value, only reaches composite-curve boundaries in STEP and would leave edge
    // pcurves as they are.)  Edges with a bare 3D curve, and all edges on planes, get
    // computed pcurves in both modes, so --curves changes nothing for them.
    set_xstep_statics(g_curves_3d ? 3 : 0);
    // Nothing here corresponds to read.iges.bspline.continuity: the STEP translator
    // (StepToGeom) keeps B-splines as written, whatever their continuity.  Nor to
    // read.iges.onlyvisible: STEP has no blanked flag (invisibility is presentation
    // data, which STEPControl_Reader does not read).  The read.step.* parameters keep
    // their defaults: products are the roots (read.step.product.mode 1) and every
    // representation (shape.repr 1) of every assembly level (assembly.level 1) is
    // transferred with its placement (root.transformation 1), so an assembly gives
    // every placed part, as IGES 408 subfigure instances do.

    // Read through a stream so that a BOM can be skipped (OCCT's lexer chokes on it).
    std::ifstream in(path, std::ios::binary);
    if (!in || !in.seekg(skip))
        throw InputError(strf("cannot open model '%s': %s", path, strerror(errno)));
    STEPControl_Reader reader;
    IFSelect_ReturnStatus st = IFSelect_RetError;
    try {
        st = reader.ReadStream(path, in);
    } catch (const Standard_Failure& e) {
        throw InputError(strf("OCCT failed to parse '%s' as STEP: %s", path, occt_what(e).c_str()));
    }
    // Stop here on any failure: after a failed read the reader's model may be null,
    // and OCCT 7.6 dereferences it without checking (FileUnits crashed in a test).
    if (st != IFSelect_RetDone || reader.StepModel().IsNull())
        throw InputError(strf("OCCT could not read '%s' as STEP (status %d: %s)", path, static_cast<int>(st),
                              read_status_text(st)));

    m.format = "STEP";
    // Length units of the file's representation contexts, for the "# file unit" line.
    // A file may hold several (one per part of an assembly); all are listed.
    try {
        TColStd_SequenceOfAsciiString len, ang, solid;
        reader.FileUnits(len, ang, solid);
        for (int i = 1; i <= len.Length(); i++) {
            if (!m.unit_name.empty()) m.unit_name += ",";
            m.unit_name += len(i).ToCString();
        }
    } catch (const Standard_Failure& e) {
        warn("'%s': could not list the STEP length units (%s)", path, occt_what(e).c_str());
    }
    int nroots = reader.NbRootsForTransfer();
    if (nroots <= 0)
        throw InputError(strf("'%s': OCCT found no transferable STEP entities (no product definition "
                              "or shape representation to translate)", path));
    int ntransferred = 0;
    try {
        ntransferred = reader.TransferRoots();
        m.shape = reader.OneShape();
    } catch (const Standard_Failure& e) {
        throw InputError(strf("OCCT failed to transfer '%s': %s", path, occt_what(e).c_str()));
    }
    if (ntransferred < nroots)
        warn("'%s': OCCT transferred %d of %d STEP roots (use -v for its messages)", path, ntransferred, nroots);
    return ntransferred;
}

Model load_model(const char* path) {
    check_readable_file(path, "model");
    std::streamoff skip = 0;
    const bool step = sniff_step(path, skip);
    if (!step) sniff_iges(path);

    Model m;
    const int nroots = step ? read_step(path, skip, m) : read_iges(path, m);
    if (m.shape.IsNull())
        throw InputError(strf("'%s': OCCT produced no shape (%d %s roots transferred)", path, nroots, m.format));
    TopExp::MapShapes(m.shape, TopAbs_FACE, m.faces);
    if (m.faces.Extent() == 0)
        throw InputError(strf("'%s': the model has no faces (%d %s roots transferred)", path, nroots, m.format));

    compute_boxes(m);
    m.diag = std::sqrt(sq(m.box.hi[0] - m.box.lo[0]) + sq(m.box.hi[1] - m.box.lo[1]) + sq(m.box.hi[2] - m.box.lo[2]));
    if (!(m.diag > 0) || !std::isfinite(m.diag))
        throw InputError(strf("'%s': degenerate bounding box (diagonal %g)", path, m.diag));
    return m;
}

void print_unit_note(const Model& m) {
    const char* unit = m.unit_name.empty() ? "?" : m.unit_name.c_str();
    if (strcmp(m.format, "STEP") == 0)
        note("STEP file; file unit: %s; all lengths below are millimetres; trim curves: %s", unit,
             g_curves_3d ? "3d (forced)" : "pcurves of the file where given");
    else
        note("file unit: %s (IGES unit flag %d); all lengths below are millimetres; trim curves: %s", unit,
             m.unit_flag, g_curves_3d ? "3d (forced)" : "as the file prefers");
}

// ---------------------------------------------------------------------------------
// Distance from a point to the trimmed faces of the model
// ---------------------------------------------------------------------------------

// Distances below this (relative to the model diagonal) count as "on the model":
// the search stops there instead of looking for an even smaller distance.  The value
// reported is still a true distance to a face, so it is within 1e-9*diag of exact.
// (`points` lowers it to 1% of its tolerance when that is smaller.)
const double kStopRel = 1e-9;
// Seed points (see FaceDistance) over all faces; the per-face grid adapts to this.
const double kSeedBudget = 300000;

// Number of knot spans of a knot vector that overlap [lo, hi].
int knot_spans(const TColStd_Array1OfReal& k, double lo, double hi) {
    int n = 0;
    for (int i = k.Lower(); i < k.Upper(); i++)
        if (k(i + 1) > lo && k(i) < hi) n++;
    return n;
}

// Lengths of the u- and v-isolines of surface s over [u0,u1] x [v0,v1], times
// `scale`: the longest of three isolines each way, as polylines of 8 points per knot
// span (32 to 512 points).  It sizes patches and sampling grids, so an estimate is
// enough.
void iso_lengths(const Handle(Geom_Surface)& s, double u0, double u1, double v0, double v1, double scale,
                 double& lu, double& lv) {
    int nu = 32, nv = 32;
    Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(s);
    if (!bs.IsNull()) {
        nu = std::max(32, std::min(512, 8 * knot_spans(bs->UKnots(), u0, u1)));
        nv = std::max(32, std::min(512, 8 * knot_spans(bs->VKnots(), v0, v1)));
    }
    lu = lv = 0;
    for (int k = 0; k < 3; k++) {
        const double v = v0 + (v1 - v0) * k / 2, u = u0 + (u1 - u0) * k / 2;
        double a = 0, b = 0;
        gp_Pnt pa = s->Value(u0, v), pb = s->Value(u, v0);
        for (int i = 1; i <= nu; i++) {
            gp_Pnt q = s->Value(u0 + (u1 - u0) * i / nu, v);
            a += pa.Distance(q);
            pa = q;
        }
        for (int i = 1; i <= nv; i++) {
            gp_Pnt q = s->Value(u, v0 + (v1 - v0) * i / nv);
            b += pb.Distance(q);
            pb = q;
        }
        lu = std::max(lu, a * scale);
        lv = std::max(lv, b * scale);
    }
}

// Length of curve c over [f, l], times `scale`: a polyline of 8 points per knot span
// (16 to 512 points).
double curve_length(const Handle(Geom_Curve)& c, double f, double l, double scale) {
    int n = 16;
    GeomAdaptor_Curve gc(c, f, l);
    if (gc.GetType() == GeomAbs_BSplineCurve)
        n = std::max(16, std::min(512, 8 * knot_spans(gc.BSpline()->Knots(), f, l)));
    double len = 0;
    gp_Pnt prev = c->Value(f);
    for (int k = 1; k <= n; k++) {
        gp_Pnt q = c->Value(f + (l - f) * k / n);
        len += prev.Distance(q);
        prev = q;
    }
    return len * scale;
}

// Exact distance from points to the union of the trimmed faces.
//
// For one face F on surface S, the nearest point of F is either an interior critical
// point of the distance to S that lies on F, or a point of F's boundary, so
//
//     dist(p, F) = min( nearest extremum of |p - S(u,v)| classified IN/ON F,
//                       distance to the boundary edge curves of F ).
//
// The extrema come from OCCT's Extrema package (see extrema(): closed form for
// analytic surfaces, a global grid + Newton search over a UV patch otherwise) and are
// classified against the trim loops with BRepTopAdaptor_FClass2d; the edges are
// projected with GeomAPI_ProjectPointOnCurve.
// This is the decomposition BRepExtrema_DistShapeShape(vertex, face) uses; calling
// DistShapeShape itself costs ~4 ms because it rebuilds its extrema grids every time,
// so the projectors here are built once and reused, and DistShapeShape is only the
// fallback for faces whose projector or edges cannot be set up.  Note that the nearest
// extremum alone is not enough even when it classifies IN: it may be a maximum or a
// far critical point while the real minimum sits on the boundary -- hence the edges,
// which cost nothing when their boxes are farther than the distance already found.
//
// Which faces are evaluated: every patch (see add_patches) whose box is closer than
// the best distance so far, near-first through a BVH, so the result is exact as long
// as the boxes contain their geometry; this subsumes "test the faces whose enlarged box
// contains the point, else all faces".  To keep that to about one evaluation per
// point on the model, the patches holding the seeds (points inside every face) nearest
// to the query are evaluated first; a distance below the stop threshold ends the
// search.
class FaceDistance {
public:
    // stop: see kStopRel.
    FaceDistance(const Model& m, double stop) {
        Stopwatch sw;
        const int n = m.faces.Extent();
        faces_.resize(static_cast<size_t>(n));
        stop_ = stop;
        nudge_ = std::max(kNudgeRel * m.diag, 10 * Precision::Confusion());
        const int g = std::max(2, std::min(12, static_cast<int>(std::lround(std::sqrt(kSeedBudget / n)))));
        // Boxes are padded by a hair for the rounding (and optimiser slack) of the box
        // computations: the pruning is only exact if no face pokes out of its boxes.
        const double pad = 1e-6 * m.diag;
        pad_ = pad;
        edge_target_ = kPatchRel * m.diag;
        std::vector<Box3> items;
        for (int i = 0; i < n; i++) {
            FaceRec& r = faces_[static_cast<size_t>(i)];
            r.face = TopoDS::Face(m.faces(i + 1));
            prepare(r, i + 1);
            Box3 fb = search_box(r.face, m.face_boxes[static_cast<size_t>(i)], pad);
            add_patches(r, i, fb, pad, kPatchRel * m.diag, items);
            if (r.usable) add_seeds(r, g);
        }
        // Edge pieces are BVH items too, after the patches (see consider()).
        TopTools_IndexedMapOfShape seen;  // an edge shared by two faces is measured once
        for (int i = 0; i < n; i++)
            if (faces_[static_cast<size_t>(i)].usable) add_edges(i, seen);
        for (const EdgeRec& e : edges_) items.push_back(e.box);
        bvh_.build(items);
        std::vector<Box3> sb(seeds_.size());
        for (size_t k = 0; k < seeds_.size(); k++) sb[k].add(seeds_[k].p);
        seed_bvh_.build(sb);
        prepare_seconds_ = sw.seconds();
    }

    struct Result {
        double dist = HUGE_VAL;
        int face = 0;  // OCCT face index (1-based), 0 when nothing was found
    };

    Result distance(const V3& p) {
        Result res;
        double best = HUGE_VAL;
        stamp_++;
        int first[kSeedPatches];
        int ns = seed_patches(p, first);
        bool done = false;
        for (int k = 0; k < ns && !done; k++) done = consider(first[k], p, best, res);
        if (!done)
            bvh_.nearest(p, best, [&](int item, double, double&) { return consider(item, p, best, res); });
        res.dist = best;
        return res;
    }

    long long projections() const { return projections_; }
    long long edge_projections() const { return edge_projections_; }
    long long fallbacks() const { return fallbacks_; }
    long long failures() const { return failures_; }
    long long nudges() const { return nudges_; }
    size_t seeds() const { return seeds_.size(); }
    size_t patches() const { return patches_.size(); }
    double prepare_seconds() const { return prepare_seconds_; }

private:
    static constexpr int kSeedPatches = 3;     // patches of the nearest seeds tried first
    static constexpr int kSeedK = 8;           // nearest seeds looked at to find them
    static constexpr double kPatchRel = 0.02;  // target patch box size, relative to diag
    static constexpr int kMaxPatchDiv = 8;     // size-based patches: at most 8 x 8 per face
    static constexpr int kMaxSplineDiv = 512;  // length-based B-spline patches: per direction
    static constexpr int kMaxFacePatches = 4096;
    static constexpr int kMaxEdgePieces = 256; // pieces of one edge (see add_edges)
    static constexpr size_t kMaxLiveEdges = 20000;  // live edge piece projectors
    static constexpr size_t kMaxLive = 1000;   // live patch projectors (~150 KB each at worst)
    static constexpr double kNudgeRel = 1e-8;  // see nearest_inside

    // A piece [a, b] of an edge's 3D curve.
    struct EdgeRec {
        int face = 0;              // a face it bounds (index into faces_)
        Handle(Geom_Curve) curve;  // in the edge's own frame
        double a = 0, b = 0;
        gp_Trsf to_local;
        double scale = 1;
        Box3 box;                  // contains the piece (world)
        V3 p0, p1;                 // piece end points (world)
        // Built on first use, dropped when too many are alive (see edge_projector()).
        std::unique_ptr<GeomAPI_ProjectPointOnCurve> proj;
    };
    struct FaceRec {
        TopoDS_Face face;
        Handle(Geom_Surface) surf;  // surface in the face's own frame (parameter space of the pcurves)
        gp_Trsf to_local;           // world -> surface frame
        gp_Trsf to_world;
        double scale = 1;           // world length = local length * scale
        double u0 = 0, u1 = 0, v0 = 0, v1 = 0;  // UV box of the face (pcurves)
        int first_patch = 0, du = 1, dv = 1;    // patches: first_patch + a*dv + b
        std::unique_ptr<BRepTopAdaptor_FClass2d> cls;
        std::unique_ptr<GeomAdaptor_Surface> adaptor;  // the surface, for Extrema
        GeomAbs_SurfaceType stype = GeomAbs_OtherSurface;
        enum Kind { kAnalytic, kSpline, kGeneral } kind = kGeneral;  // see extrema()
        bool usable = false;        // projector/classifier available
        unsigned stamp = 0;         // query that last measured this face with DistShapeShape
        unsigned proj_stamp = 0;    // kAnalytic: query that last projected on this face
        // The boundary edges are edge pieces (edges_), unless one of them cannot be
        // measured (no 3D curve...): then DistShapeShape measures the whole face.
        bool edges_ok = true;
    };
    struct Patch {
        int face = 0;
        double a0 = 0, a1 = 0, b0 = 0, b1 = 0;  // UV rectangle, with a margin
        int nbu = 0, nbv = 0;                   // sampling grid (B-spline/Bezier patches)
        // Built on first use, dropped when too many are alive (see projector()).
        std::unique_ptr<Extrema_GenExtPS> gen;  // kSpline: minima only, small grid
        std::unique_ptr<Extrema_ExtPS> ext;     // kGeneral
        unsigned stamp = 0;
    };
    struct Seed {
        V3 p;
        int patch;
    };

    // ---- setup ----

    void prepare(FaceRec& r, int index) {
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
            r.to_world = loc.Transformation();
            r.scale = std::fabs(r.to_world.ScaleFactor());
            r.to_local = r.to_world.Inverted();
            BRepTools::UVBounds(r.face, r.u0, r.u1, r.v0, r.v1);
            if (!(r.u1 > r.u0) || !(r.v1 > r.v0)) throw Standard_Failure("empty UV box");
            r.cls.reset(new BRepTopAdaptor_FClass2d(r.face, Precision::PConfusion()));
            r.adaptor.reset(new GeomAdaptor_Surface(r.surf));
            r.stype = r.adaptor->GetType();
            switch (r.stype) {
            case GeomAbs_Plane: case GeomAbs_Cylinder: case GeomAbs_Cone: case GeomAbs_Sphere: case GeomAbs_Torus:
                r.kind = FaceRec::kAnalytic;
                break;
            case GeomAbs_BSplineSurface: case GeomAbs_BezierSurface:
                r.kind = FaceRec::kSpline;
                break;
            default:
                r.kind = FaceRec::kGeneral;
            }
            r.usable = true;
        } catch (const Standard_Failure& e) {
            warn("face %d: cannot prepare projection (%s); using BRepExtrema for it", index,
                 occt_what(e).c_str());
            r.usable = false;
        }
    }

    // The face-level box.  B-spline and Bezier faces get AddOptimal (their pole boxes
    // are loose); it is cheap for them, unlike for surfaces of revolution.  The result
    // is intersected with the containing box: both contain the face.
    static Box3 search_box(const TopoDS_Face& f, const Box3& containing, double pad) {
        Box3 b = containing;
        try {
            GeomAbs_SurfaceType t = BRepAdaptor_Surface(f, Standard_False).GetType();
            if (t == GeomAbs_BSplineSurface || t == GeomAbs_BezierSurface) {
                Bnd_Box ob;
                BRepBndLib::AddOptimal(f, ob, Standard_False, Standard_True);  // with tolerances
                if (!ob.IsVoid()) {
                    Box3 o = to_box3(ob);
                    for (int k = 0; k < 3; k++) {
                        b.lo[k] = std::max(b.lo[k], o.lo[k]);
                        b.hi[k] = std::min(b.hi[k], o.hi[k]);
                    }
                    if (!(b.lo[0] <= b.hi[0] && b.lo[1] <= b.hi[1] && b.lo[2] <= b.hi[2])) b = containing;
                }
            }
        } catch (const Standard_Failure&) {
            b = containing;
        }
        for (int k = 0; k < 3; k++) {
            b.lo[k] -= pad;
            b.hi[k] += pad;
        }
        return b;
    }

    // Patches: the BVH items and the unit of projection.  A big face has one box that
    // contains many query points although the face is far from most of them, and a
    // B-spline with hundreds of knot spans (a thread: 529 poles, 65 extrema per point)
    // costs ~3 ms per global projection.  So the face's UV box is cut into patches of
    // about kPatchRel*diag (at most 8 x 8), B-splines also one per knot span (at most
    // 64 per direction, 256 per face); each patch gets its own containing box (control
    // point hull of the segmented B-spline/Bezier, analytic bounds otherwise), clipped
    // to the face box and grown by the largest edge tolerance (edge curves may stray
    // that far from the surface), and its own projector on its UV rectangle.
    void add_patches(FaceRec& r, int item, const Box3& fb, double pad, double target, std::vector<Box3>& items) {
        r.first_patch = static_cast<int>(patches_.size());
        r.du = r.dv = 1;
        if (r.usable) {
            double size = std::sqrt(sq(fb.hi[0] - fb.lo[0]) + sq(fb.hi[1] - fb.lo[1]) + sq(fb.hi[2] - fb.lo[2]));
            int du = std::max(1, std::min(kMaxPatchDiv, static_cast<int>(std::ceil(size / target))));
            int dv = du;
            if (r.kind == FaceRec::kSpline) {
                // Size from the 3D lengths of the isolines, not from the face box: the box
                // of a long, thin, curved face (a helical spring's wire: 780 x 8 mm in a
                // 35 x 35 x 72 mm box) says nothing about its shape, and a patch spanning
                // a quarter turn has a box that contains every query point near that
                // quarter turn, so each of them gets projected on dozens of patches.
                double lu = 0, lv = 0;
                iso_lengths(r.surf, r.u0, r.u1, r.v0, r.v1, r.scale, lu, lv);
                du = std::max(1, std::min(kMaxSplineDiv, static_cast<int>(std::ceil(lu / target))));
                dv = std::max(1, std::min(kMaxSplineDiv, static_cast<int>(std::ceil(lv / target))));
            }
            Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(r.surf);
            if (!bs.IsNull()) {
                du = std::max(du, std::min(64, knot_spans(bs->UKnots(), r.u0, r.u1)));
                dv = std::max(dv, std::min(64, knot_spans(bs->VKnots(), r.v0, r.v1)));
            }
            while (du * dv > kMaxFacePatches) {
                if (du >= dv) du = (du + 1) / 2;
                else dv = (dv + 1) / 2;
            }
            try {
                std::vector<Box3> boxes;
                std::vector<Patch> ps;
                for (int a = 0; a < du; a++)
                    for (int b = 0; b < dv; b++) {
                        Patch pt;
                        pt.face = item;
                        pt.a0 = r.u0 + (r.u1 - r.u0) * a / du;
                        pt.a1 = r.u0 + (r.u1 - r.u0) * (a + 1) / du;
                        pt.b0 = r.v0 + (r.v1 - r.v0) * b / dv;
                        pt.b1 = r.v0 + (r.v1 - r.v0) * (b + 1) / dv;
                        // Margin: an extremum on the line between two patches is then
                        // interior to both rectangles, so the search finds it.
                        double mu = 1e-3 * (pt.a1 - pt.a0), mv = 1e-3 * (pt.b1 - pt.b0);
                        pt.a0 -= mu; pt.a1 += mu; pt.b0 -= mv; pt.b1 += mv;
                        clamp_to_surface(r, pt.a0, pt.a1, pt.b0, pt.b1);
                        grid_size(r, pt);
                        const Box3 own = (du * dv == 1) ? fb : patch_box(r, pt.a0, pt.a1, pt.b0, pt.b1, pad);
                        Box3 pb = own;
                        for (int k = 0; k < 3; k++) {
                            pb.lo[k] = std::max(pb.lo[k], fb.lo[k]);
                            pb.hi[k] = std::min(pb.hi[k], fb.hi[k]);
                        }
                        // An empty intersection means that this part of the untrimmed
                        // surface is outside the face's box (the face is trimmed away
                        // here: the Spring's wire is cut by a plane across its UV box).
                        // Keep the patch's own box: it contains the patch, and it is
                        // far from the face.  (The face box, used here before, contains
                        // every query near the face and made such patches be projected
                        // for all of them.)
                        if (!(pb.lo[0] <= pb.hi[0] && pb.lo[1] <= pb.hi[1] && pb.lo[2] <= pb.hi[2])) pb = own;
                        boxes.push_back(pb);
                        ps.push_back(std::move(pt));
                    }
                for (size_t k = 0; k < ps.size(); k++) {
                    items.push_back(boxes[k]);
                    patches_.push_back(std::move(ps[k]));
                }
                r.du = du;
                r.dv = dv;
                return;
            } catch (const Standard_Failure&) {
                // fall back to one patch over the whole face
            }
        }
        Patch pt;
        pt.face = item;
        pt.a0 = r.u0; pt.a1 = r.u1; pt.b0 = r.v0; pt.b1 = r.v1;
        if (r.usable) {
            double mu = 1e-3 * (r.u1 - r.u0), mv = 1e-3 * (r.v1 - r.v0);
            pt.a0 -= mu; pt.a1 += mu; pt.b0 -= mv; pt.b1 += mv;
            clamp_to_surface(r, pt.a0, pt.a1, pt.b0, pt.b1);
            grid_size(r, pt);
        }
        items.push_back(fb);
        patches_.push_back(std::move(pt));
    }

    // Sampling grid of a B-spline/Bezier patch for Extrema_GenExtPS: about two samples
    // per polynomial degree and knot span inside the patch, 8..44 per direction.
    // (Extrema_ExtPS always uses 44 x 44, and 300 along a degenerate iso: ~0.35-2.5 MB
    // per projector, which multiplied by thousands of patches is gigabytes.)
    static void grid_size(const FaceRec& r, Patch& pt) {
        Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(r.surf);
        Handle(Geom_BezierSurface) bz = Handle(Geom_BezierSurface)::DownCast(r.surf);
        int su = 1, sv = 1, deg_u = 3, deg_v = 3;
        if (!bs.IsNull()) {
            su = std::max(1, knot_spans(bs->UKnots(), pt.a0, pt.a1));
            sv = std::max(1, knot_spans(bs->VKnots(), pt.b0, pt.b1));
            deg_u = bs->UDegree();
            deg_v = bs->VDegree();
        } else if (!bz.IsNull()) {
            deg_u = bz->UDegree();
            deg_v = bz->VDegree();
        }
        pt.nbu = std::max(8, std::min(44, 2 * (deg_u + 1) * su));
        pt.nbv = std::max(8, std::min(44, 2 * (deg_v + 1) * sv));
    }

    static void clamp_to_surface(const FaceRec& r, double& a0, double& a1, double& b0, double& b1) {
        double su0, su1, sv0, sv1;
        r.surf->Bounds(su0, su1, sv0, sv1);
        if (!r.surf->IsUPeriodic()) { a0 = std::max(a0, su0); a1 = std::min(a1, su1); }
        if (!r.surf->IsVPeriodic()) { b0 = std::max(b0, sv0); b1 = std::min(b1, sv1); }
        if (!(a1 > a0) || !(b1 > b0)) throw Standard_Failure("UV box outside the surface");
    }

    // Containing box of the surface over a UV rectangle, in world coordinates.
    static Box3 patch_box(const FaceRec& r, double a0, double a1, double b0, double b1, double grow) {
        Bnd_Box b;
        Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(r.surf);
        Handle(Geom_BezierSurface) bz = Handle(Geom_BezierSurface)::DownCast(r.surf);
        if (!bs.IsNull()) {
            // convex hull property (weights are positive): the poles of the segment bound it
            Handle(Geom_BSplineSurface) c = Handle(Geom_BSplineSurface)::DownCast(bs->Copy());
            c->Segment(a0, a1, b0, b1);
            for (int i = 1; i <= c->NbUPoles(); i++)
                for (int j = 1; j <= c->NbVPoles(); j++) b.Add(c->Pole(i, j));
        } else if (!bz.IsNull()) {
            Handle(Geom_BezierSurface) c = Handle(Geom_BezierSurface)::DownCast(bz->Copy());
            c->Segment(a0, a1, b0, b1);
            for (int i = 1; i <= c->NbUPoles(); i++)
                for (int j = 1; j <= c->NbVPoles(); j++) b.Add(c->Pole(i, j));
        } else {
            GeomAdaptor_Surface ga(r.surf, a0, a1, b0, b1);
            BndLib_AddSurface::Add(ga, 0.0, b);
            GeomAbs_SurfaceType t = ga.GetType();
            if (t != GeomAbs_Plane && t != GeomAbs_Cylinder && t != GeomAbs_Cone && t != GeomAbs_Sphere &&
                t != GeomAbs_Torus)
                b.Enlarge(0.1 * std::sqrt(b.SquareExtent()));  // sampled by OCCT: see containing_box
        }
        if (b.IsVoid()) throw Standard_Failure("empty patch box");
        b.Enlarge(grow);
        if (r.to_world.Form() != gp_Identity) b = b.Transformed(r.to_world);
        return to_box3(b);
    }

    // Cell centres of a g x g grid over the face's UV box that classify IN.
    void add_seeds(const FaceRec& r, int g) {
        try {
            for (int i = 0; i < g; i++)
                for (int j = 0; j < g; j++) {
                    double u = r.u0 + (r.u1 - r.u0) * (i + 0.5) / g;
                    double v = r.v0 + (r.v1 - r.v0) * (j + 0.5) / g;
                    if (r.cls->Perform(gp_Pnt2d(u, v)) != TopAbs_IN) continue;
                    gp_Pnt q = r.surf->Value(u, v).Transformed(r.to_world);
                    int a = std::min(r.du - 1, static_cast<int>((u - r.u0) / (r.u1 - r.u0) * r.du));
                    int b = std::min(r.dv - 1, static_cast<int>((v - r.v0) / (r.v1 - r.v0) * r.dv));
                    seeds_.push_back({V3(q), r.first_patch + a * r.dv + b});
                }
        } catch (const Standard_Failure&) {
            // seeds only order the search; a face without seeds is still searched
        }
    }

    // Adds the pieces of the boundary edges of face i that are not in `seen` yet.
    // Each edge is cut into pieces of about kPatchRel*diag (at most kMaxEdgePieces),
    // each with its own box and projector.  The box of a whole long edge (the
    // Spring's helical edges are 650 to 900 mm long) contains every query point near
    // the face, and one projection on such a curve costs ~0.1 ms and has to find one
    // extremum per turn from a few samples.
    void add_edges(int i, TopTools_IndexedMapOfShape& seen) {
        FaceRec& r = faces_[static_cast<size_t>(i)];
        try {
            for (TopExp_Explorer ex(r.face, TopAbs_EDGE); ex.More(); ex.Next()) {
                const TopoDS_Edge& e = TopoDS::Edge(ex.Current());
                if (BRep_Tool::Degenerated(e)) continue;  // a pole: its point ends other edges
                TopLoc_Location loc;
                double f, l;
                Handle(Geom_Curve) c = BRep_Tool::Curve(e, loc, f, l);
                if (c.IsNull() || !(l > f)) {  // no 3D curve
                    r.edges_ok = false;
                    continue;
                }
                if (seen.Contains(e)) continue;
                const gp_Trsf t = loc.Transformation();
                const double scale = std::fabs(t.ScaleFactor());
                const GeomAbs_CurveType ct = GeomAdaptor_Curve(c, f, l).GetType();
                // Short edges (the box diagonal says so) are one piece; for the others
                // the length is estimated with a polyline of 8 points per knot span
                // (16 to 512 points).
                const Box3 whole = curve_box(c, ct, f, l, t, pad_);
                int pieces = 1;
                if (whole.diag() > edge_target_) {
                    const double len = curve_length(c, f, l, scale);
                    pieces = std::max(1, std::min(kMaxEdgePieces, static_cast<int>(std::ceil(len / edge_target_))));
                }
                for (int k = 0; k < pieces; k++) {
                    EdgeRec er;
                    er.face = i;
                    er.curve = c;
                    er.a = f + (l - f) * k / pieces;
                    er.b = k + 1 == pieces ? l : f + (l - f) * (k + 1) / pieces;
                    er.scale = scale;
                    er.to_local = t.Inverted();
                    er.p0 = V3(c->Value(er.a).Transformed(t));
                    er.p1 = V3(c->Value(er.b).Transformed(t));
                    er.box = pieces == 1 ? whole : curve_box(c, ct, er.a, er.b, t, pad_);
                    edges_.push_back(std::move(er));
                }
                seen.Add(e);
            }
        } catch (const Standard_Failure& ex) {
            // The pieces added so far are true distances to the edge; DistShapeShape
            // covers the rest of the face.
            warn("face %d: cannot prepare its edges (%s); using BRepExtrema for it", i + 1, occt_what(ex).c_str());
            r.edges_ok = false;
        }
    }

    // A box that contains the curve over [a, b], in world coordinates: control point
    // hull of the segment for B-splines and Bezier curves, OCCT's exact box for
    // lines and conics, and OCCT's sampled box plus 10% for anything else.
    static Box3 curve_box(const Handle(Geom_Curve)& c, GeomAbs_CurveType ct, double a, double b, const gp_Trsf& t,
                          double pad) {
        Bnd_Box bb;
        GeomAdaptor_Curve gc(c, a, b);
        if (ct == GeomAbs_BSplineCurve) {
            Handle(Geom_BSplineCurve) s = Handle(Geom_BSplineCurve)::DownCast(gc.BSpline()->Copy());
            s->Segment(a, b);
            for (int i = 1; i <= s->NbPoles(); i++) bb.Add(s->Pole(i));
        } else if (ct == GeomAbs_BezierCurve) {
            Handle(Geom_BezierCurve) s = Handle(Geom_BezierCurve)::DownCast(gc.Bezier()->Copy());
            // Bezier parameters are always [0, 1]
            s->Segment(a, b);
            for (int i = 1; i <= s->NbPoles(); i++) bb.Add(s->Pole(i));
        } else {
            BndLib_Add3dCurve::Add(gc, 0.0, bb);
            if (ct != GeomAbs_Line && ct != GeomAbs_Circle && ct != GeomAbs_Ellipse)
                bb.Enlarge(0.1 * std::sqrt(bb.SquareExtent()));
        }
        if (bb.IsVoid()) throw Standard_Failure("empty edge box");
        bb.Enlarge(pad);
        if (t.Form() != gp_Identity) bb = bb.Transformed(t);
        return to_box3(bb);
    }

    // ---- queries ----

    // Patches of the seeds nearest to p, nearest first.
    int seed_patches(const V3& p, int out[kSeedPatches]) const {
        double kd[kSeedK];
        int ki[kSeedK];
        int cnt = 0;
        double bound = HUGE_VAL;
        seed_bvh_.nearest(p, bound, [&](int item, double, double& b) {
            double d = norm(seeds_[static_cast<size_t>(item)].p - p);
            if (cnt == kSeedK && d >= kd[kSeedK - 1]) return false;
            int k = cnt < kSeedK ? cnt++ : kSeedK - 1;
            while (k > 0 && kd[k - 1] > d) {
                kd[k] = kd[k - 1];
                ki[k] = ki[k - 1];
                k--;
            }
            kd[k] = d;
            ki[k] = item;
            if (cnt == kSeedK) b = kd[kSeedK - 1];
            return false;
        });
        int n = 0;
        for (int k = 0; k < cnt && n < kSeedPatches; k++) {
            int pt = seeds_[static_cast<size_t>(ki[k])].patch;
            if (std::find(out, out + n, pt) == out + n) out[n++] = pt;
        }
        return n;
    }

    void improve(double d, int face_item, double& best, Result& res) {
        if (d < best) {
            best = d;
            res.face = face_item + 1;
        }
    }

    // Evaluates one patch (and, the first time its face is met for this point, the
    // face's boundary edges).  Returns true when the search can stop.
    bool consider(int item, const V3& p, double& best, Result& res) {
        if (static_cast<size_t>(item) >= patches_.size()) {
            consider_edge(edges_[static_cast<size_t>(item) - patches_.size()], p, best, res);
            return best <= stop_;
        }
        Patch& pt = patches_[static_cast<size_t>(item)];
        if (pt.stamp == stamp_) return best <= stop_;
        pt.stamp = stamp_;
        FaceRec& r = faces_[static_cast<size_t>(pt.face)];
        // an analytic face is projected as a whole: once per point is enough
        const bool skip = r.kind == FaceRec::kAnalytic && r.proj_stamp == stamp_;
        r.proj_stamp = stamp_;
        if (r.usable && !skip) {
            bool ok = false;
            try {
                double d;
                ok = nearest_inside(r, pt, p, best, d);
                if (ok) improve(d, pt.face, best, res);
            } catch (const Standard_Failure&) {
                ok = false;
            }
            if (!ok && r.stamp != stamp_) {
                // No answer even from nudged points: BRepExtrema decides this face
                // for this point.
                failures_++;
                r.stamp = stamp_;
                improve(dist_shape_shape(r, p), pt.face, best, res);
            }
        }
        if ((!r.usable || !r.edges_ok) && r.stamp != stamp_) {
            r.stamp = stamp_;
            improve(dist_shape_shape(r, p), pt.face, best, res);
        }
        return best <= stop_;
    }

    // Distance to an edge piece: its end points and the extrema inside it.
    void consider_edge(EdgeRec& e, const V3& p, double& best, Result& res) {
        if (e.box.dist(p) >= best) return;
        edge_projections_++;
        double d = std::min(norm(p - e.p0), norm(p - e.p1));
        try {
            GeomAPI_ProjectPointOnCurve& pr = edge_projector(e);
            pr.Perform(p.pnt().Transformed(e.to_local));
            if (pr.NbPoints() > 0) d = std::min(d, pr.LowerDistance() * e.scale);
        } catch (const Standard_Failure&) {
            failures_++;
            FaceRec& r = faces_[static_cast<size_t>(e.face)];
            if (r.stamp != stamp_) {
                r.stamp = stamp_;
                d = std::min(d, dist_shape_shape(r, p));
            }
        }
        improve(d, e.face, best, res);
    }

    // The piece's projector, created if needed; at most kMaxLiveEdges at a time.
    GeomAPI_ProjectPointOnCurve& edge_projector(EdgeRec& e) {
        if (!e.proj) {
            e.proj.reset(new GeomAPI_ProjectPointOnCurve());
            e.proj->Init(e.curve, e.a, e.b);
            live_edges_.push_back(static_cast<int>(&e - edges_.data()));
            if (live_edges_.size() > kMaxLiveEdges) {
                edges_[static_cast<size_t>(live_edges_.front())].proj.reset();
                live_edges_.pop_front();
            }
        }
        return *e.proj;
    }

    // d = distance to the nearest extremum on the patch that classifies IN/ON the
    // face (HUGE_VAL if none is closer than `best`); false if OCCT could not project.
    // Extrema are classified nearest first and only while they can still win:
    // classification costs ~0.3 ms on long trim loops and a B-spline projection may
    // report dozens of extrema.
    //
    // OCCT reports "not done" when the point has infinitely many nearest points: on
    // the axis of a cylinder, cone or surface of revolution, at the centre of a
    // sphere -- common in CAD, e.g. the centre of a hole's end cap.  The point is then
    // nudged by kNudgeRel*diag and projected again.  Distances are always measured
    // from the ORIGINAL point to the surface points found, so a nudged answer is a
    // true distance to the face and within 2*nudge of the exact one (the distance is
    // 1-Lipschitz in the point).
    bool nearest_inside(FaceRec& r, Patch& pt, const V3& p, double best, double& d_out) {
        static const V3 dirs[3] = {V3(0.5773502691896258, 0.5773502691896258, 0.5773502691896258),
                                   V3(0.8017837257372732, -0.5345224838248488, 0.2672612419124244),
                                   V3(-0.2672612419124244, 0.8017837257372732, 0.5345224838248488)};
        d_out = HUGE_VAL;
        bool done = extrema(r, pt, p);
        for (int k = 0; !done && k < 3; k++) {
            nudges_++;
            done = extrema(r, pt, p + nudge_ * dirs[k]);
        }
        if (!done) return false;
        order_.clear();
        for (size_t k = 0; k < uv_.size(); k++) {
            double d = norm(p - V3(r.surf->Value(uv_[k].X(), uv_[k].Y()).Transformed(r.to_world)));
            if (std::isfinite(d) && d < best) order_.push_back({d, static_cast<int>(k)});
        }
        std::sort(order_.begin(), order_.end());
        for (const auto& o : order_) {
            TopAbs_State st = r.cls->Perform(uv_[static_cast<size_t>(o.second)]);
            if (st == TopAbs_IN || st == TopAbs_ON) {
                d_out = o.first;
                break;
            }
        }
        return true;
    }

    // Extrema of the distance from p (world) to the surface, as UV points in uv_;
    // false when OCCT could not answer.  Three engines:
    //   kAnalytic  plane, cylinder, cone, sphere, torus: closed form (Extrema_ExtPElS)
    //              on the whole surface; the classifier brings periodic parameters
    //              back into the face's range.
    //   kSpline    B-spline/Bezier: Extrema_GenExtPS on the patch rectangle with a
    //              small grid (see grid_size), minima only.
    //   kGeneral   revolution, extrusion, offset...: Extrema_ExtPS on the patch
    //              rectangle (it has dedicated algorithms for the first two).
    bool extrema(FaceRec& r, Patch& pt, const V3& p) {
        projections_++;
        uv_.clear();
        const gp_Pnt q = p.pnt().Transformed(r.to_local);
        double u, v;
        if (r.kind == FaceRec::kAnalytic) {
            Extrema_ExtPElS e;
            const double tol = Precision::Confusion();
            switch (r.stype) {
            case GeomAbs_Plane: e.Perform(q, r.adaptor->Plane(), tol); break;
            case GeomAbs_Cylinder: e.Perform(q, r.adaptor->Cylinder(), tol); break;
            case GeomAbs_Cone: e.Perform(q, r.adaptor->Cone(), tol); break;
            case GeomAbs_Sphere: e.Perform(q, r.adaptor->Sphere(), tol); break;
            default: e.Perform(q, r.adaptor->Torus(), tol); break;
            }
            if (!e.IsDone()) return false;
            for (int k = 1; k <= e.NbExt(); k++) {
                e.Point(k).Parameter(u, v);
                uv_.emplace_back(u, v);
            }
            return true;
        }
        projector(r, pt);
        if (pt.gen) {
            pt.gen->Perform(q);
            if (!pt.gen->IsDone()) return false;
            for (int k = 1; k <= pt.gen->NbExt(); k++) {
                pt.gen->Point(k).Parameter(u, v);
                uv_.emplace_back(u, v);
            }
        } else {
            pt.ext->Perform(q);
            if (!pt.ext->IsDone()) return false;
            for (int k = 1; k <= pt.ext->NbExt(); k++) {
                pt.ext->Point(k).Parameter(u, v);
                uv_.emplace_back(u, v);
            }
        }
        return true;
    }

    // Creates the patch's projector if needed.  At most kMaxLive exist at a time, the
    // oldest being dropped (and rebuilt if needed again): memory stays bounded on
    // models with tens of thousands of patches, and points usually come face by face.
    void projector(FaceRec& r, Patch& pt) {
        if (pt.gen || pt.ext) return;
        const double pc = Precision::PConfusion();
        if (r.kind == FaceRec::kSpline) {
            pt.gen.reset(new Extrema_GenExtPS());
            pt.gen->SetFlag(Extrema_ExtFlag_MIN);  // only minima can be the nearest point
            pt.gen->SetAlgo(Extrema_ExtAlgo_Grad);
            pt.gen->Initialize(*r.adaptor, pt.nbu, pt.nbv, pt.a0, pt.a1, pt.b0, pt.b1, pc, pc);
        } else {
            pt.ext.reset(new Extrema_ExtPS());
            pt.ext->Initialize(*r.adaptor, pt.a0, pt.a1, pt.b0, pt.b1, pc, pc);
        }
        live_.push_back(static_cast<int>(&pt - patches_.data()));
        if (live_.size() > kMaxLive) {
            Patch& old = patches_[static_cast<size_t>(live_.front())];
            old.gen.reset();
            old.ext.reset();
            live_.pop_front();
        }
    }

    // Whole-face fallback.
    double dist_shape_shape(const FaceRec& r, const V3& p) {
        fallbacks_++;
        try {
            TopoDS_Vertex v = BRepBuilderAPI_MakeVertex(p.pnt()).Vertex();
            BRepExtrema_DistShapeShape dss(v, r.face, Extrema_ExtFlag_MIN);
            if (dss.IsDone() && dss.NbSolution() > 0) return dss.Value();
        } catch (const Standard_Failure&) {
        }
        failures_++;
        return HUGE_VAL;
    }

    std::vector<FaceRec> faces_;
    std::vector<Patch> patches_;
    Bvh bvh_;
    std::vector<Seed> seeds_;
    Bvh seed_bvh_;
    std::vector<std::pair<double, int>> order_;
    std::vector<gp_Pnt2d> uv_;  // extrema of the current projection
    std::deque<int> live_;
    std::vector<EdgeRec> edges_;  // BVH items patches_.size() + k
    std::deque<int> live_edges_;
    double stop_ = 0;
    double nudge_ = 0;
    double pad_ = 0;          // box padding for rounding (see the constructor)
    double edge_target_ = 0;  // edge piece length (see add_edges)
    unsigned stamp_ = 0;
    double prepare_seconds_ = 0;
    long long projections_ = 0, edge_projections_ = 0, fallbacks_ = 0, failures_ = 0, nudges_ = 0;
};

void print_search_stats(const Model& m, const FaceDistance& fd) {
    note("diag %.10g mm, %d OCCT faces, %zu patches, %zu seeds; %lld surface projections (%lld nudged), "
         "%lld edge projections, %lld BRepExtrema fallbacks, %lld failures",
         m.diag, m.faces.Extent(), fd.patches(), fd.seeds(), fd.projections(), fd.nudges(), fd.edge_projections(),
         fd.fallbacks(), fd.failures());
}

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

// Parses a strictly positive integer (whole string), at most 1e12.
long long parse_count(const std::string& s, const char* what) {
    errno = 0;
    char* end = nullptr;
    long long v = strtoll(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || errno == ERANGE || v < 1 || v > 1000000000000LL)
        throw UsageError(strf("%s must be a positive integer, got '%s'", what, s.c_str()));
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
    if (a.pos.size() != 1) throw UsageError("info needs exactly one argument: MODEL");
    double sew_rel = 1e-6;
    if (a.opt.count("--sew-rel")) sew_rel = parse_positive(a.opt.at("--sew-rel"), "--sew-rel");
    Stopwatch sw;
    Model m = load_model(a.pos[0].c_str());
    double t_read = sw.seconds();

    TopTools_IndexedMapOfShape shells, solids;
    TopExp::MapShapes(m.shape, TopAbs_SHELL, shells);
    TopExp::MapShapes(m.shape, TopAbs_SOLID, solids);
    // Largest tolerance OCCT attached to the model (after its shape healing): edge
    // curves may be that far from the surfaces they bound, so distances of points
    // near face boundaries are only defined to about this much.
    double max_tol = 0;
    for (int i = 1; i <= m.faces.Extent(); i++) {
        const TopoDS_Face& f = TopoDS::Face(m.faces(i));
        max_tol = std::max(max_tol, BRep_Tool::Tolerance(f));
        for (TopExp_Explorer ex(f, TopAbs_EDGE); ex.More(); ex.Next())
            max_tol = std::max(max_tol, BRep_Tool::Tolerance(TopoDS::Edge(ex.Current())));
        for (TopExp_Explorer ex(f, TopAbs_VERTEX); ex.More(); ex.Next())
            max_tol = std::max(max_tol, BRep_Tool::Tolerance(TopoDS::Vertex(ex.Current())));
    }

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
    kv("max_tol", max_tol);
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
            // |c| > 1e12 mm is garbage for a CAD part, and squares of it overflow
            if (end == s || errno == ERANGE || !std::isfinite(c[k]) || std::fabs(c[k]) > 1e12) ok = false;
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
            throw InputError(strf("%s:%lld: expected 'x y z face_id' (3 numbers within +-1e12 and an integer), got '%s'",
                                  path, lineno, shown.c_str()));
        }
        pts.push_back({V3(c[0], c[1], c[2]), id});
    }
    if (in.bad()) throw InputError(strf("error reading '%s'", path));
    if (pts.empty()) throw InputError(strf("'%s' contains no points", path));
    return pts;
}

int cmd_points(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("points needs MODEL POINTS.xyz");
    double tol_rel = 1e-6;
    if (a.opt.count("--tol-rel")) tol_rel = parse_positive(a.opt.at("--tol-rel"), "--tol-rel");
    std::vector<InPoint> pts = read_points(a.pos[1].c_str());  // cheap: fail early on bad input
    // --out: one line per point, for finding the bad ones (opened before the model
    // read, so that a wrong path fails fast)
    std::unique_ptr<FILE, int (*)(FILE*)> dump(nullptr, fclose);
    if (a.opt.count("--out")) {
        dump.reset(fopen(a.opt.at("--out").c_str(), "w"));
        if (!dump) throw InputError(strf("cannot write '%s': %s", a.opt.at("--out").c_str(), strerror(errno)));
        fprintf(dump.get(), "# x y z face_id distance nearest_occt_face\n");
    }
    Stopwatch sw;
    Model m = load_model(a.pos[0].c_str());
    double t_read = sw.seconds();
    const double tol = tol_rel * m.diag;

    FaceDistance fd(m, std::min(kStopRel * m.diag, 0.01 * tol));
    double t_prep = fd.prepare_seconds();

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
            fprintf(dump.get(), "%.17g %.17g %.17g %lld %.10g %d\n", ip.p.x, ip.p.y, ip.p.z, ip.id, d, r.face);
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
    if (dump && fclose(dump.release()) != 0) throw InputError(strf("error writing '%s'", a.opt.at("--out").c_str()));

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
    print_search_stats(m, fd);
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

// Meshes the model with OCCT, face by face.  Linear deflection is absolute
// (defl_rel * diag), the angle 0.5 rad unless told (write-stl --angle: make bench coarsens Open
// CASCADE's mesh to a measured deviation, and at 0.5 rad the angle, not the deflection, decides
// how finely most curved faces are meshed).
//
// One BRepMesh_IncrementalMesh call for the whole shape ran for more than 10 minutes
// on occt__bug22869_Spring (--curves 3d or not) and took 1.6 GB, in BRepMesh_Delaun's
// frontierAdjust on one of the two long helical faces, and then gave that face no
// triangles anyway.  Meshed on its own, the same face fails at once
// (IMeshData_SelfIntersectingWire).  So every face is meshed by its own call; faces
// that still get no triangles are sampled by sample_face_grid instead.  The calls are
// sequential: BRepMesh's parallel mode works across the faces of one call.
void mesh_model(const Model& m, double defl, double angle = 0.5) {
    for (int i = 1; i <= m.faces.Extent(); i++) {
        try {
            BRepMesh_IncrementalMesh mesher(m.faces(i), defl, Standard_False, angle, Standard_False);
        } catch (const Standard_Failure& e) {
            warn("face %d: BRepMesh failed: %s", i, occt_what(e).c_str());
        }
    }
}

// A point on the model, in world coordinates, with its face.
struct ModelSample {
    V3 p;
    int face;
};

// Points on a face that BRepMesh could not triangulate: the centres of a UV grid
// whose cells are about h long on the surface (from the isoline lengths; at most
// kMaxGridPerFace cells), kept when they classify IN or ON the face, plus points
// every h along the 3D curves of its edges.  Returns how many were added.
long long sample_face_grid(const TopoDS_Face& f, int index, double h, std::vector<ModelSample>& out) {
    const long long kMaxGridPerFace = 100000;
    const size_t before = out.size();
    TopLoc_Location loc;
    Handle(Geom_Surface) s = BRep_Tool::Surface(f, loc);
    if (s.IsNull()) return 0;
    const gp_Trsf t = loc.Transformation();
    const double scale = std::fabs(t.ScaleFactor());
    double u0, u1, v0, v1;
    BRepTools::UVBounds(f, u0, u1, v0, v1);
    if (u1 > u0 && v1 > v0) {
        double lu = 0, lv = 0;
        iso_lengths(s, u0, u1, v0, v1, scale, lu, lv);
        long long nu = std::max(1LL, std::min(100000LL, static_cast<long long>(std::ceil(lu / h))));
        long long nv = std::max(1LL, std::min(100000LL, static_cast<long long>(std::ceil(lv / h))));
        while (nu * nv > kMaxGridPerFace) {
            if (nu >= nv) nu = (nu + 1) / 2;
            else nv = (nv + 1) / 2;
        }
        BRepTopAdaptor_FClass2d cls(f, Precision::PConfusion());
        for (long long i = 0; i < nu; i++)
            for (long long j = 0; j < nv; j++) {
                const double u = u0 + (u1 - u0) * (static_cast<double>(i) + 0.5) / static_cast<double>(nu);
                const double v = v0 + (v1 - v0) * (static_cast<double>(j) + 0.5) / static_cast<double>(nv);
                if (cls.Perform(gp_Pnt2d(u, v)) == TopAbs_OUT) continue;
                out.push_back({V3(s->Value(u, v).Transformed(t)), index});
            }
    }
    for (TopExp_Explorer ex(f, TopAbs_EDGE); ex.More(); ex.Next()) {
        const TopoDS_Edge& e = TopoDS::Edge(ex.Current());
        if (BRep_Tool::Degenerated(e)) continue;
        TopLoc_Location eloc;
        double a, b;
        Handle(Geom_Curve) c = BRep_Tool::Curve(e, eloc, a, b);
        if (c.IsNull() || !(b > a)) continue;
        const gp_Trsf et = eloc.Transformation();
        const double len = curve_length(c, a, b, std::fabs(et.ScaleFactor()));
        const long long n = std::max(1LL, std::min(100000LL, static_cast<long long>(std::ceil(len / h))));
        for (long long k = 0; k <= n; k++)
            out.push_back({V3(c->Value(a + (b - a) * static_cast<double>(k) / static_cast<double>(n)).Transformed(et)), index});
    }
    return static_cast<long long>(out.size() - before);
}

// Points on the model for model -> mesh: for every face that BRepMesh triangulated,
// the tessellation vertices plus one point per triangle.  The per-triangle point is
// the triangle's UV centroid mapped through the surface, so it lies ON the model
// (the 3D centroid would be off the surface by up to the deflection, and that sag
// would be blamed on MESH).  Faces without UV nodes fall back to the 3D centroid.
//
// BRepMesh's triangles are not always inside their face in UV: on the Spring it
// joins boundary nodes across the bulge of a trim curve, and the UV centroid of such
// a sliver maps to the untrimmed surface 2.2 mm off the model.  So the UV centroid of
// every triangle with a node on the boundary is classified, and dropped (counted in
// `outside`) when it is OUT.  Faces without triangles get sample_face_grid with
// spacing `grid_h`.
std::vector<ModelSample> model_samples(const Model& m, double grid_h,
                                       std::vector<std::pair<int, long long>>& grid_faces, long long& outside) {
    std::vector<ModelSample> out;
    grid_faces.clear();
    outside = 0;
    for (int i = 1; i <= m.faces.Extent(); i++) {
        const TopoDS_Face& f = TopoDS::Face(m.faces(i));
        TopLoc_Location loc;
        Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(f, loc);
        if (tri.IsNull() || tri->NbTriangles() == 0) {
            long long got = 0;
            try {
                got = sample_face_grid(f, i, grid_h, out);
            } catch (const Standard_Failure& e) {
                warn("face %d: grid sampling failed: %s", i, occt_what(e).c_str());
            }
            grid_faces.emplace_back(i, got);
            continue;
        }
        gp_Trsf t = loc.Transformation();
        for (int k = 1; k <= tri->NbNodes(); k++) out.push_back({V3(tri->Node(k).Transformed(t)), i});
        TopLoc_Location sloc;
        Handle(Geom_Surface) s = BRep_Tool::Surface(f, sloc);
        gp_Trsf st = sloc.Transformation();
        // boundary nodes: those of the edges' polygons on this triangulation (all
        // nodes count as boundary if an edge has none)
        std::vector<char> bnd(static_cast<size_t>(tri->NbNodes()) + 1, 0);
        for (TopExp_Explorer ex(f, TopAbs_EDGE); ex.More(); ex.Next()) {
            TopLoc_Location eloc;
            Handle(Poly_PolygonOnTriangulation) pp =
                BRep_Tool::PolygonOnTriangulation(TopoDS::Edge(ex.Current()), tri, eloc);
            if (pp.IsNull()) {
                std::fill(bnd.begin(), bnd.end(), 1);
                break;
            }
            for (int k = 1; k <= pp->NbNodes(); k++) {
                int nd = pp->Node(k);
                if (nd >= 1 && nd <= tri->NbNodes()) bnd[static_cast<size_t>(nd)] = 1;
            }
        }
        std::unique_ptr<BRepTopAdaptor_FClass2d> cls;
        for (int k = 1; k <= tri->NbTriangles(); k++) {
            int n1, n2, n3;
            tri->Triangle(k).Get(n1, n2, n3);
            gp_Pnt c;
            bool done = false;
            if (tri->HasUVNodes() && !s.IsNull()) {
                gp_XY uv = (tri->UVNode(n1).XY() + tri->UVNode(n2).XY() + tri->UVNode(n3).XY()) / 3.0;
                try {
                    if (bnd[static_cast<size_t>(n1)] || bnd[static_cast<size_t>(n2)] || bnd[static_cast<size_t>(n3)]) {
                        if (!cls) cls.reset(new BRepTopAdaptor_FClass2d(f, Precision::PConfusion()));
                        if (cls->Perform(gp_Pnt2d(uv.X(), uv.Y())) == TopAbs_OUT) {
                            outside++;
                            continue;
                        }
                    }
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

// Indices of an evenly strided subset of n of `total` items (all of them if n is 0
// or not smaller): floor(k*total/n), k = 0..n-1.  Deterministic, and spread over the
// whole list, whatever its order.
std::vector<size_t> strided(size_t total, size_t n) {
    std::vector<size_t> idx;
    if (n == 0 || n >= total) {
        idx.resize(total);
        for (size_t k = 0; k < total; k++) idx[k] = k;
        return idx;
    }
    idx.resize(n);
    for (size_t k = 0; k < n; k++)
        idx[k] = static_cast<size_t>(static_cast<unsigned long long>(k) * total / n);
    return idx;
}

int cmd_mesh_dev(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("mesh-dev needs MODEL MESH.stl");
    double defl_rel = 1e-4;
    if (a.opt.count("--defl-rel")) defl_rel = parse_positive(a.opt.at("--defl-rel"), "--defl-rel");
    long long max_points = 0;  // 0: no cap
    if (a.opt.count("--max-points")) max_points = parse_count(a.opt.at("--max-points"), "--max-points");
    Stopwatch sw;
    TriMesh mesh(read_stl(a.pos[1].c_str()));
    Model m = load_model(a.pos[0].c_str());
    double t_read = sw.seconds();

    // (a) mesh -> model: unique mesh vertices (STL repeats them per triangle) and
    // triangle centroids; with --max-points, a strided subset of that list.
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
    const std::vector<size_t> qa = strided(q.size(), static_cast<size_t>(max_points));

    FaceDistance fd(m, kStopRel * m.diag);
    WorstK<V3> worst_a(10);
    double max_a = 0, sum_a = 0;
    long long unresolved = 0;
    // per OCCT face (index-1): the worst mesh point whose nearest face it is, the worst
    // sample of it, and the box of its samples (for --per-face-out)
    const size_t nf = static_cast<size_t>(m.faces.Extent());
    std::vector<double> face_a(nf, 0.0), face_b(nf, 0.0);
    std::vector<Box3> face_box(nf);
    std::vector<double> dq(q.size(), std::nan(""));  // each measured point's distance
    for (size_t k : qa) {
        const V3& p = q[k];
        FaceDistance::Result r = fd.distance(p);
        double d = r.dist;
        dq[k] = d;
        if (!std::isfinite(d)) unresolved++;
        if (r.face >= 1 && static_cast<size_t>(r.face) <= nf && std::isfinite(d))
            face_a[static_cast<size_t>(r.face - 1)] = std::max(face_a[static_cast<size_t>(r.face - 1)], d);
        max_a = std::max(max_a, d);
        sum_a += d;
        worst_a.add(d, p);
    }
    double t_a = sw2.seconds();

    // (b) model -> mesh
    Stopwatch sw3;
    const double defl = defl_rel * m.diag;
    mesh_model(m, defl);
    std::vector<std::pair<int, long long>> grid_faces;
    // grid spacing for faces BRepMesh fails on: the chord with sagitta `defl` on a
    // radius of diag/8
    long long outside = 0;
    std::vector<ModelSample> ms = model_samples(m, std::sqrt(defl * m.diag), grid_faces, outside);
    const std::vector<size_t> qb = strided(ms.size(), static_cast<size_t>(max_points));
    WorstK<ModelSample> worst_b(10);
    double max_b = 0, sum_b = 0;
    for (size_t k : qb) {
        const ModelSample& s = ms[k];
        double d = mesh.distance(s.p);
        if (s.face >= 1 && static_cast<size_t>(s.face) <= nf)
            face_b[static_cast<size_t>(s.face - 1)] = std::max(face_b[static_cast<size_t>(s.face - 1)], d);
        max_b = std::max(max_b, d);
        sum_b += d;
        worst_b.add(d, s);
    }
    double t_b = sw3.seconds();
    if (a.opt.count("--mesh-faces")) {
        // per face of the MESH (`cmz decode --face-map`: its triangle counts in STL order): the box
        // of its triangles and its worst point (vertices and centroids), i.e. each mesh point
        // judged against the face it was rebuilt for, not the nearest true face
        const std::string& in = a.opt.at("--mesh-faces");
        const std::string out = a.opt.count("--mesh-faces-out") ? a.opt.at("--mesh-faces-out") : in + ".dev";
        FILE* f = fopen(in.c_str(), "r");
        if (!f) throw InputError(strf("cannot read '%s': %s", in.c_str(), strerror(errno)));
        std::vector<std::pair<long, long>> mf;  // (face number, triangles)
        char line[256];
        while (fgets(line, sizeof line, f)) {
            long id, n;
            if (sscanf(line, "%ld %ld", &id, &n) == 2 && n >= 0) mf.emplace_back(id, n);
        }
        fclose(f);
        long long total = 0;
        for (const auto& e : mf) total += e.second;
        if (total != static_cast<long long>(mesh.tris().size()))
            throw InputError(strf("'%s' lists %lld triangles, the mesh has %zu", in.c_str(), total, mesh.tris().size()));
        FILE* o = fopen(out.c_str(), "w");
        if (!o) throw InputError(strf("cannot write '%s': %s", out.c_str(), strerror(errno)));
        fprintf(o, "mesh_face\tbox_diag\tmesh_to_model_max\n");
        const auto vbegin = q.begin(), vend = q.begin() + static_cast<long>(nverts);
        auto dist_of = [&](const V3& v) {
            auto it = std::lower_bound(vbegin, vend, v, lt);
            return it != vend && eq(*it, v) ? dq[static_cast<size_t>(it - q.begin())] : std::nan("");
        };
        size_t t = 0;
        for (const auto& e : mf) {
            Box3 b;
            double worst = 0;
            for (long k = 0; k < e.second; k++, t++) {
                const Tri& tr = mesh.tris()[t];
                b.add(tr.a);
                b.add(tr.b);
                b.add(tr.c);
                for (double d : {dist_of(tr.a), dist_of(tr.b), dist_of(tr.c), dq[nverts + t]})
                    if (std::isfinite(d)) worst = std::max(worst, d);
            }
            fprintf(o, "%ld\t%.10g\t%.10g\n", e.first, e.second ? b.diag() : 0.0, worst);
        }
        if (fclose(o) != 0) throw InputError(strf("cannot write '%s': %s", out.c_str(), strerror(errno)));
    }
    if (a.opt.count("--per-face-out")) {
        // the box of every sample (BRepMesh nodes and the UV centroids), a tight inner
        // box of the face; the loose containing box where a face has no sample
        for (const ModelSample& s : ms)
            if (s.face >= 1 && static_cast<size_t>(s.face) <= nf) face_box[static_cast<size_t>(s.face - 1)].add(s.p);
        const std::string& path = a.opt.at("--per-face-out");
        FILE* f = fopen(path.c_str(), "w");
        if (!f) throw InputError(strf("cannot write '%s': %s", path.c_str(), strerror(errno)));
        fprintf(f, "face\tbox_diag\tmesh_to_model_max\tmodel_to_mesh_max\n");
        for (size_t i = 0; i < nf; i++) {
            const Box3& b = face_box[i].lo[0] <= face_box[i].hi[0] ? face_box[i] : m.face_boxes[i];
            fprintf(f, "%zu\t%.10g\t%.10g\t%.10g\n", i + 1, b.diag(), face_a[i], face_b[i]);
        }
        if (fclose(f) != 0) throw InputError(strf("cannot write '%s': %s", path.c_str(), strerror(errno)));
    }

    print_unit_note(m);
    kv("diag", m.diag);
    kv("mesh_triangles", static_cast<long long>(mesh.tris().size()));
    kv("mesh_vertices", static_cast<long long>(nverts));
    kv("mesh_to_model_points", static_cast<long long>(qa.size()));
    kv("mesh_to_model_total", static_cast<long long>(q.size()));
    kv("mesh_to_model_max", max_a);
    kv("mesh_to_model_mean", qa.empty() ? 0.0 : sum_a / static_cast<double>(qa.size()));
    kv("model_defl", defl);
    kv("model_to_mesh_points", static_cast<long long>(qb.size()));
    kv("model_to_mesh_total", static_cast<long long>(ms.size()));
    kv("model_to_mesh_max", max_b);
    kv("model_to_mesh_mean", qb.empty() ? 0.0 : sum_b / static_cast<double>(qb.size()));
    kv("model_grid_faces", static_cast<long long>(grid_faces.size()));
    for (const auto& w : worst_a.items())
        note("worst mesh_to_model: %.10g %.10g %.10g %.10g", w.second.x, w.second.y, w.second.z, w.first);
    for (const auto& w : worst_b.items())
        note("worst model_to_mesh: %.10g %.10g %.10g occt_face %d %.10g", w.second.p.x, w.second.p.y,
             w.second.p.z, w.second.face, w.first);
    if (unresolved) note("%lld mesh points: OCCT found no distance (reported as inf)", unresolved);
    if (outside)
        note("%lld OCCT triangles have their UV centroid outside their face (not used)", outside);
    for (const auto& g : grid_faces)
        note("face %d: BRepMesh gave no triangles; %lld points from a UV grid and the edges instead", g.first,
             g.second);
    if (max_points > 0 && (qa.size() < q.size() || qb.size() < ms.size()))
        note("--max-points %lld: measured every %.3g-th mesh point and every %.3g-th model point", max_points,
             static_cast<double>(q.size()) / static_cast<double>(qa.size()),
             static_cast<double>(ms.size()) / static_cast<double>(std::max<size_t>(1, qb.size())));
    print_search_stats(m, fd);
    note("time: read %.2f s, mesh->model %.2f s, model->mesh %.2f s", t_read, t_a, t_b);
    return 0;
}

// ---------------------------------------------------------------------------------
// sample
// ---------------------------------------------------------------------------------

int cmd_sample(const Args& a) {
    if (a.pos.size() != 2) throw UsageError("sample needs MODEL OUT.xyz");
    long long per_face = 20;
    if (a.opt.count("--per-face")) {
        const std::string& s = a.opt.at("--per-face");
        char* end = nullptr;
        errno = 0;
        per_face = strtoll(s.c_str(), &end, 10);
        if (s.empty() || *end || errno || per_face < 1 || per_face > 1000000)
            throw UsageError(strf("--per-face must be an integer in 1..1000000, got '%s'", s.c_str()));
    }
    // Open the output first: a typo in its path should not cost a model read.
    FILE* out = fopen(a.pos[1].c_str(), "w");
    if (!out) throw InputError(strf("cannot write '%s': %s", a.pos[1].c_str(), strerror(errno)));
    std::unique_ptr<FILE, int (*)(FILE*)> guard(out, fclose);
    Model m = load_model(a.pos[0].c_str());
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
    if (fclose(guard.release()) != 0) throw InputError(strf("error writing '%s'", a.pos[1].c_str()));
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
    if (a.pos.size() != 2) throw UsageError("write-stl needs MODEL OUT.stl");
    double defl_rel = 1e-4;
    if (a.opt.count("--defl-rel")) defl_rel = parse_positive(a.opt.at("--defl-rel"), "--defl-rel");
    double angle = 0.5;
    if (a.opt.count("--angle")) angle = parse_positive(a.opt.at("--angle"), "--angle");
    Model m = load_model(a.pos[0].c_str());
    mesh_model(m, defl_rel * m.diag, angle);

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
    "  info     MODEL [--sew-rel R]                faces, shells, solids, bbox, diag, free_edges\n"
    "                                               (faces sewn at R*diag, default 1e-6)\n"
    "  points   MODEL POINTS.xyz [--tol-rel R]      distance of 'x y z face_id' points to the faces\n"
    "                    [--out FILE]               (default R 1e-6; exit 1 if any point > R*diag;\n"
    "                                               FILE gets every point's distance and nearest face)\n"
    "  mesh-dev MODEL MESH.stl [--defl-rel R]       two-sided deviation mesh <-> model\n"
    "                    [--max-points N]           (model tessellated at R*diag, default 1e-4;\n"
    "                                               N: measure at most N evenly strided points\n"
    "                                               each way, default all)\n"
    "                    [--per-face-out F.tsv]     per OCCT face: box diagonal, worst\n"
    "                                               mesh point nearest it, worst sample of it\n"
    "                    [--mesh-faces F.tsv [--mesh-faces-out O.tsv]]  per face of the mesh\n"
    "                                               (cmz decode --face-map): its box, its worst point\n"
    "  sample   MODEL OUT.xyz [--per-face N]        N points (default 20) inside every face\n"
    "MODEL is an IGES or a STEP (ISO 10303-21) file, recognised by its content.\n"
    "Every command also takes --curves file|3d: trim curves as the file gives them\n"
    "(default) or rebuilt from the 3D curves.\n"
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
    // --curves is accepted by every command
    auto args = [&](std::vector<std::string> known) {
        known.push_back("--curves");
        Args a = parse_args(argc, argv, first + 1, known);
        if (a.opt.count("--curves")) {
            const std::string& c = a.opt.at("--curves");
            if (c == "file") g_curves_3d = false;
            else if (c == "3d") g_curves_3d = true;
            else throw UsageError(strf("--curves must be 'file' or '3d', got '%s'", c.c_str()));
        }
        return a;
    };
    if (cmd == "info") return cmd_info(args({"--sew-rel"}));
    if (cmd == "points") return cmd_points(args({"--tol-rel", "--out"}));
    if (cmd == "mesh-dev")
        return cmd_mesh_dev(args({"--defl-rel", "--max-points", "--per-face-out", "--mesh-faces", "--mesh-faces-out"}));
    if (cmd == "sample") return cmd_sample(args({"--per-face"}));
    if (cmd == "write-stl") return cmd_write_stl(args({"--defl-rel", "--angle"}));
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

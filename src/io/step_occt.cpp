/*
 * step_occt.cpp - STEP files through Open CASCADE: sem_step_read and sem_step_write
 * (sem/model.h). The only C++ file of libsem; everything Open CASCADE is kept in here, behind
 * those two C functions, so the rest of the library stays C and builds without it
 * (src/io/step_stub.c, SEM_WITH_OCCT=OFF).
 *
 * Reading. STEPControl_Reader translates the file into a B-rep shape (solids, shells or free
 * faces, assemblies flattened with their placements), and each face becomes one part. A face
 * on an analytic surface is converted by BRepBuilderAPI_NurbsConvert (planes, cylinders,
 * cones, spheres, tori, extrusions and revolutions exactly, offset surfaces approximately;
 * its curves on the surface follow the new parameters); a B-spline face is taken as it is,
 * because the conversion can move a curve's end along a pole (a gap it leaves along a
 * collapsed edge is closed by a connector, as the projection of model-space trims does).
 * A part is: its surface with the face's placement applied, its outer wire as the outer
 * trim loop and its other wires as holes, each edge contributing its curve on the face (the
 * "pcurve"). An edge without one (a file that gives model-space edges only) gets one from
 * ShapeFix_Edge, which projects the 3D curve into the face. A reversed face has its surface
 * reversed in u and its loops mirrored with it, so x_u x x_v points out of the solid as it does
 * in the file. An outer wire that is just the border of the surface's domain is dropped (the
 * part is untrimmed, as an IGES reader would see it). Lengths stay in the file's unit (the
 * reader is told that the session unit is the file's), and the model records that unit.
 * As for every reader (sem/limits.h), only a regular file of at most SEM_MAX_MODEL_FILE_BYTES
 * is handed to Open CASCADE, and the model it gives must pass sem_model_check_limits (parts,
 * knot spans) with every surface within SEM_MAX_PART_CONTROL_POINTS.
 *
 * Writing. Each part becomes a face: its B-spline surface, and for a trimmed part edges made
 * from the loop curves on that surface (3D curves computed from them), joined into wires by
 * ShapeFix_Wire (our loops close within a tolerance, not by shared vertices) and oriented by
 * ShapeFix_Face. The faces go out as one compound in the model's unit.
 *
 * Why a mutex: Open CASCADE's translators keep their settings (units, modes) in process-wide
 * statics (Interface_Static), so two translations at once would see each other's settings.
 * Open CASCADE reports problems by throwing Standard_Failure; every entry point catches it
 * and returns one sem_error message.
 */
#include <strings.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <Bnd_Box.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepLib.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <ShapeExtend_WireData.hxx>
#include <ShapeFix_Edge.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Wire.hxx>
#include <Standard_Failure.hxx>
#include <StepData_StepModel.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax2d.hxx>
#include <gp_Pnt2d.hxx>

extern "C" {
#include "geometry/net_size.h"
#include "geometry/trim_fix.h"
#include "io/atomic_file.h"
#include "io/read_file.h"
#include "sem/limits.h"
#include "sem/model.h"
#include "sem/trim.h"
}

namespace {

std::mutex occt_mutex;

/* Open CASCADE's translators report progress and statistics through the default messenger,
 * whose printer writes to standard output: a library must not. The printers are taken off
 * for the duration of one call (under occt_mutex) and put back, so a program that uses
 * Open CASCADE itself keeps its own output. */
class quiet_messenger {
public:
    quiet_messenger() : messenger(Message::DefaultMessenger())
    {
        if (messenger.IsNull()) return;
        saved = messenger->Printers();
        messenger->ChangePrinters().Clear();
    }
    ~quiet_messenger()
    {
        if (messenger.IsNull()) return;
        messenger->ChangePrinters() = saved;
    }
    quiet_messenger(const quiet_messenger &) = delete;
    quiet_messenger &operator=(const quiet_messenger &) = delete;

private:
    Handle(Message_Messenger) messenger;
    Message_SequenceOfPrinters saved;
};

/* One Interface_Static setting changed for the duration of a call and put back after, so a
 * program that uses Open CASCADE's translators itself keeps its own settings. */
class static_setting {
public:
    static_setting(const char *name, const char *value) : name(name)
    {
        const char *old = Interface_Static::CVal(name);
        had = old != nullptr;
        if (had) saved = old;
        Interface_Static::SetCVal(name, value);
    }
    ~static_setting()
    {
        if (had) Interface_Static::SetCVal(name, saved.c_str());
    }
    static_setting(const static_setting &) = delete;
    static_setting &operator=(const static_setting &) = delete;

private:
    const char *name;
    std::string saved;
    bool had = false;
};

/* ---- units: STEP/Open CASCADE names <-> the model's unit name and metres ---- */

struct unit_name {
    const char *ours;  /* sem_model.units, as the IGES reader names them */
    const char *occt;  /* Interface_Static "write.step.unit" value */
    double mm;         /* one unit in millimetres */
};

const unit_name UNITS[] = {
    {"MM", "MM", 1.0},      {"M", "M", 1000.0},        {"CM", "CM", 10.0},
    {"IN", "INCH", 25.4},   {"FT", "FT", 304.8},       {"MI", "MI", 1609344.0},
    {"KM", "KM", 1e6},      {"MIL", "MIL", 0.0254},    {"UM", "UM", 1e-3},
    {"UIN", "UIN", 2.54e-5}};

const unit_name *unit_by_mm(double mm)
{
    for (const unit_name &u : UNITS)
        if (std::fabs(u.mm - mm) <= 1e-9 * u.mm) return &u;
    return nullptr;
}

/* A length unit as FileUnits names it: an SI unit with its prefix ("metre", "millimetre"),
 * or a conversion-based unit's own name ("INCH", "FOOT"), any case. */
const unit_name *unit_by_step_name(const char *name)
{
    static const struct {
        const char *name;
        double mm;
    } names[] = {{"millimetre", 1.0}, {"millimeter", 1.0}, {"mm", 1.0},   {"metre", 1000.0},
                 {"meter", 1000.0},   {"m", 1000.0},      {"centimetre", 10.0},
                 {"centimeter", 10.0}, {"cm", 10.0},      {"kilometre", 1e6}, {"kilometer", 1e6},
                 {"km", 1e6},          {"micrometre", 1e-3}, {"micrometer", 1e-3}, {"um", 1e-3},
                 {"inch", 25.4},       {"in", 25.4},      {"foot", 304.8},  {"feet", 304.8},
                 {"ft", 304.8},        {"mile", 1609344.0}, {"mil", 0.0254}};
    for (const auto &n : names)
        if (strcasecmp(name, n.name) == 0) return unit_by_mm(n.mm);
    return nullptr;
}

const unit_name *unit_of_model(const sem_model *m)
{
    for (const unit_name &u : UNITS)
        if (m->units[0] && strcasecmp(m->units, u.ours) == 0) return &u;
    if (m->unit_to_meter > 0) return unit_by_mm(1000.0 * m->unit_to_meter);
    return nullptr;
}

/* ---- Open CASCADE -> sem ---- */

std::vector<double> flat_knots(const TColStd_Array1OfReal &knots, const TColStd_Array1OfInteger &mults)
{
    std::vector<double> out;
    for (int i = knots.Lower(); i <= knots.Upper(); ++i)
        for (int k = 0; k < mults(i); ++k) out.push_back(knots(i));
    return out;
}

sem_status surface_from_occt(const Handle(Geom_BSplineSurface) & b, sem_surface *s, sem_error *err)
{
    int nu = b->NbUPoles(), nv = b->NbVPoles();
    if ((long long)nu * nv > SEM_MAX_PART_CONTROL_POINTS)
        return sem_error_set(err, SEM_ERR_INVALID, "%d x %d control points; at most %d per surface "
                                                   "(limit SEM_MAX_PART_CONTROL_POINTS)",
                             nu, nv, SEM_MAX_PART_CONTROL_POINTS);
    if (sem_surface_alloc(s, b->UDegree(), b->VDegree(), nu, nv) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    TColStd_Array1OfReal uk(1, b->NbUKnots()), vk(1, b->NbVKnots());
    TColStd_Array1OfInteger um(1, b->NbUKnots()), vm(1, b->NbVKnots());
    b->UKnots(uk);
    b->VKnots(vk);
    b->UMultiplicities(um);
    b->VMultiplicities(vm);
    std::vector<double> ku = flat_knots(uk, um), kv = flat_knots(vk, vm);
    if ((int)ku.size() != nu + s->degree_u + 1 || (int)kv.size() != nv + s->degree_v + 1)
        return sem_error_set(err, SEM_ERR_INVALID, "a B-spline surface has inconsistent knots");
    std::copy(ku.begin(), ku.end(), s->knots_u);
    std::copy(kv.begin(), kv.end(), s->knots_v);
    bool rational = b->IsURational() || b->IsVRational(); /* else Weight() is not defined */
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            gp_Pnt p = b->Pole(i + 1, j + 1);
            size_t k = (size_t)i + (size_t)nu * (size_t)j;
            s->ctrl[3 * k] = p.X();
            s->ctrl[3 * k + 1] = p.Y();
            s->ctrl[3 * k + 2] = p.Z();
            s->weights[k] = rational ? b->Weight(i + 1, j + 1) : 1.0;
        }
    b->Bounds(s->u0, s->u1, s->v0, s->v1);
    return SEM_OK;
}

sem_status curve_from_occt(const Handle(Geom2d_BSplineCurve) & b, sem_curve *c, sem_error *err)
{
    int n = b->NbPoles();
    if (sem_curve_alloc(c, b->Degree(), n) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    TColStd_Array1OfReal k(1, b->NbKnots());
    TColStd_Array1OfInteger m(1, b->NbKnots());
    b->Knots(k);
    b->Multiplicities(m);
    std::vector<double> flat = flat_knots(k, m);
    if ((int)flat.size() != n + c->degree + 1)
        return sem_error_set(err, SEM_ERR_INVALID, "a trim curve has inconsistent knots");
    std::copy(flat.begin(), flat.end(), c->knots);
    bool rational = b->IsRational();
    for (int i = 0; i < n; ++i) {
        gp_Pnt2d p = b->Pole(i + 1);
        c->ctrl[3 * i] = p.X();
        c->ctrl[3 * i + 1] = p.Y();
        c->ctrl[3 * i + 2] = 0.0;
        c->weights[i] = rational ? b->Weight(i + 1) : 1.0;
    }
    c->t0 = b->FirstParameter();
    c->t1 = b->LastParameter();
    return SEM_OK;
}

/* The pcurve of an edge on a face, as a B-spline running the way the wire runs it. */
Handle(Geom2d_BSplineCurve) pcurve_of(const TopoDS_Edge &edge, const TopoDS_Face &face)
{
    Standard_Real f = 0, l = 0;
    Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, face, f, l);
    if (pc.IsNull()) {
        /* a model-space edge only: project its 3D curve into the face */
        ShapeFix_Edge fix;
        fix.FixAddPCurve(edge, face, Standard_False);
        pc = BRep_Tool::CurveOnSurface(edge, face, f, l);
        if (pc.IsNull()) return Handle(Geom2d_BSplineCurve)();
    }
    if (!(l > f)) return Handle(Geom2d_BSplineCurve)();
    Handle(Geom2d_BSplineCurve) b =
        Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(pc, f, l));
    if (b.IsNull()) return b;
    b = Handle(Geom2d_BSplineCurve)::DownCast(b->Copy());
    if (b->IsPeriodic()) b->SetNotPeriodic();
    if (edge.Orientation() == TopAbs_REVERSED) b->Reverse();
    return b;
}

/* Every point of every curve lies on the border of [u0,u1] x [v0,v1] and the loop encloses
 * the whole rectangle: the wire is the surface's own border and trims nothing. */
bool loop_is_domain_border(const std::vector<Handle(Geom2d_BSplineCurve)> &curves, double u0,
                           double u1, double v0, double v1)
{
    double eu = 1e-7 * (u1 - u0), ev = 1e-7 * (v1 - v0);
    double area = 0;
    bool have = false;
    gp_Pnt2d first, prev;
    for (const Handle(Geom2d_BSplineCurve) & c : curves) {
        double a = c->FirstParameter(), b = c->LastParameter();
        for (int k = 0; k <= 16; ++k) {
            gp_Pnt2d p = c->Value(a + (b - a) * k / 16.0);
            bool on = std::fabs(p.X() - u0) <= eu || std::fabs(p.X() - u1) <= eu ||
                      std::fabs(p.Y() - v0) <= ev || std::fabs(p.Y() - v1) <= ev;
            if (!on) return false;
            if (!have) {
                first = p;
                have = true;
            } else {
                area += prev.X() * p.Y() - p.X() * prev.Y();
            }
            prev = p;
        }
    }
    if (!have) return false;
    area += prev.X() * first.Y() - first.X() * prev.Y();
    double domain = (u1 - u0) * (v1 - v0);
    return std::fabs(std::fabs(0.5 * area) - domain) <= 1e-6 * domain;
}

sem_status loop_from_curves(const std::vector<Handle(Geom2d_BSplineCurve)> &curves,
                            sem_trim_loop *loop, sem_error *err)
{
    loop->n_curves = 0;
    loop->curves = (sem_curve *)calloc(curves.size(), sizeof(sem_curve));
    if (!loop->curves) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (const Handle(Geom2d_BSplineCurve) & c : curves) {
        sem_status st = curve_from_occt(c, &loop->curves[loop->n_curves], err);
        if (st != SEM_OK) return st;
        loop->n_curves++;
    }
    return SEM_OK;
}

/* Orders a loop's curves end to start in (u,v): from the first, each next is the remaining
 * curve whose start is nearest the current end (trim.c's closure check judges the result). */
void chain_by_ends(std::vector<Handle(Geom2d_BSplineCurve)> &curves)
{
    for (size_t k = 0; k + 1 < curves.size(); ++k) {
        gp_Pnt2d end = curves[k]->Value(curves[k]->LastParameter());
        size_t best = k + 1;
        double best_d = INFINITY;
        for (size_t j = k + 1; j < curves.size(); ++j) {
            double d = end.Distance(curves[j]->Value(curves[j]->FirstParameter()));
            if (d < best_d) best_d = d, best = j;
        }
        std::swap(curves[k + 1], curves[best]);
    }
}

/* The curves of a wire on a face, in the wire's order. Empty when an edge has no pcurve. */
std::vector<Handle(Geom2d_BSplineCurve)> wire_curves(const TopoDS_Wire &wire, const TopoDS_Face &face)
{
    std::vector<Handle(Geom2d_BSplineCurve)> out;
    std::vector<TopoDS_Edge> edges, stored;
    for (BRepTools_WireExplorer wex(wire, face); wex.More(); wex.Next()) edges.push_back(wex.Current());
    for (TopoDS_Iterator it(wire); it.More(); it.Next())
        if (it.Value().ShapeType() == TopAbs_EDGE) stored.push_back(TopoDS::Edge(it.Value()));
    /* The explorer follows the wire's vertices and stops where it cannot choose: at a
     * collapsed edge of a converted face (a cone's apex, a sphere's pole), where a side edge,
     * the collapsed edge and the other side meet within 1e-8 of each other, it gave 2 of 4
     * edges and the loop did not close (NIST CTC-01 face 57, CTC-02 face 52). Then the wire's
     * edges are taken as stored and chained by their (u,v) ends. */
    bool chain = edges.size() < stored.size();
    if (chain) edges = stored;
    for (const TopoDS_Edge &e : edges) {
        Handle(Geom2d_BSplineCurve) c = pcurve_of(e, face);
        if (c.IsNull()) {
            if (BRep_Tool::Degenerated(e)) continue;
            return std::vector<Handle(Geom2d_BSplineCurve)>();
        }
        out.push_back(c);
    }
    if (chain) chain_by_ends(out);
    return out;
}

double surface_size_occt(const Handle(Geom_BSplineSurface) & b)
{
    Bnd_Box box;
    for (int j = 1; j <= b->NbVPoles(); ++j)
        for (int i = 1; i <= b->NbUPoles(); ++i) box.Add(b->Pole(i, j));
    double size = box.IsVoid() ? 0.0 : std::sqrt(box.SquareExtent());
    return size > 0 && std::isfinite(size) ? size : 1.0;
}

/* Joins consecutive curves of a loop whose ends differ in (u,v) but meet in space along a
 * collapsed edge (a pole): a straight connector, whose image is that point. Conversions can
 * leave such gaps (NurbsConvert moves a seam edge's end along the pole of a sphere). */
void close_collapsed_gaps(std::vector<Handle(Geom2d_BSplineCurve)> &curves,
                          const Handle(Geom_BSplineSurface) & b, double precision)
{
    double u0, u1, v0, v1;
    b->Bounds(u0, u1, v0, v1);
    std::vector<Handle(Geom2d_BSplineCurve)> out;
    for (size_t k = 0; k < curves.size(); ++k) {
        out.push_back(curves[k]);
        const Handle(Geom2d_BSplineCurve) &next = curves[(k + 1) % curves.size()];
        gp_Pnt2d a = curves[k]->Value(curves[k]->LastParameter());
        gp_Pnt2d c = next->Value(next->FirstParameter());
        if (std::hypot((c.X() - a.X()) / (u1 - u0), (c.Y() - a.Y()) / (v1 - v0)) < 1e-9) continue;
        gp_Pnt pa = b->Value(a.X(), a.Y());
        bool collapsed = true;
        for (int i = 1; i <= 8 && collapsed; ++i) {
            double t = i / 8.0;
            gp_Pnt p = b->Value(a.X() + t * (c.X() - a.X()), a.Y() + t * (c.Y() - a.Y()));
            collapsed = p.Distance(pa) <= precision;
        }
        if (!collapsed) continue; /* a real gap: trim.c's closure check reports it */
        TColgp_Array1OfPnt2d poles(1, 2);
        poles(1) = a;
        poles(2) = c;
        TColStd_Array1OfReal knots(1, 2);
        TColStd_Array1OfInteger mults(1, 2);
        knots(1) = 0, knots(2) = 1, mults(1) = mults(2) = 2;
        out.push_back(new Geom2d_BSplineCurve(poles, knots, mults, 1));
    }
    curves.swap(out);
}

sem_status part_from_face(const TopoDS_Face &face_in, int index, sem_part *part, sem_model *model,
                          sem_error *err)
{
    TopoDS_Face face = face_in;
    TopLoc_Location loc;
    Handle(Geom_Surface) g = BRep_Tool::Surface(face, loc);
    if (g.IsNull()) return sem_error_set(err, SEM_ERR_INVALID, "face %d has no surface", index + 1);
    Handle(Geom_BSplineSurface) b = Handle(Geom_BSplineSurface)::DownCast(g);
    if (b.IsNull()) {
        /* an analytic or trimmed surface: convert the face, so that its curves on the
         * surface follow the B-spline's parameters (a B-spline face is taken as it is:
         * the conversion only approximates where it need not) */
        BRepBuilderAPI_NurbsConvert nurbs(face, Standard_True);
        if (nurbs.IsDone()) {
            TopExp_Explorer ex(nurbs.Shape(), TopAbs_FACE);
            if (ex.More()) face = TopoDS::Face(ex.Current());
        }
        g = BRep_Tool::Surface(face, loc);
        b = Handle(Geom_BSplineSurface)::DownCast(g);
        if (b.IsNull() && !g.IsNull()) b = GeomConvert::SurfaceToBSplineSurface(g);
    }
    if (b.IsNull())
        return sem_error_set(err, SEM_ERR_UNSUPPORTED, "face %d: surface not convertible to a NURBS",
                             index + 1);
    b = Handle(Geom_BSplineSurface)::DownCast(b->Copy());
    if (!loc.IsIdentity()) b->Transform(loc.Transformation());
    if (b->IsUPeriodic()) b->SetUNotPeriodic();
    if (b->IsVPeriodic()) b->SetVNotPeriodic();
    double u0, u1, v0, v1;
    b->Bounds(u0, u1, v0, v1);
    /* a reversed face: reverse the surface in u and mirror the loops with it */
    Handle(Geom_BSplineSurface) unreversed = b;
    double precision = 1e-6 * surface_size_occt(b);
    bool reversed = face.Orientation() == TopAbs_REVERSED;
    if (reversed) {
        b = Handle(Geom_BSplineSurface)::DownCast(b->Copy());
        b->UReverse();
    }
    gp_Ax2d mirror(gp_Pnt2d(0.5 * (u0 + u1), 0.0), gp_Dir2d(0.0, 1.0));

    memset(part, 0, sizeof *part);
    sem_status st = surface_from_occt(b, &part->surface, err);
    if (st != SEM_OK) return st;

    TopoDS_Wire outer = BRepTools::OuterWire(face);
    std::vector<std::vector<Handle(Geom2d_BSplineCurve)>> holes;
    std::vector<Handle(Geom2d_BSplineCurve)> outer_curves;
    for (TopoDS_Iterator it(face); it.More(); it.Next()) {
        if (it.Value().ShapeType() != TopAbs_WIRE) continue;
        TopoDS_Wire w = TopoDS::Wire(it.Value());
        std::vector<Handle(Geom2d_BSplineCurve)> curves = wire_curves(w, face);
        if (curves.empty()) {
            sem_model_warn(model, "face %d: a wire without parameter-space curves (and none "
                                  "could be projected); that loop is left out",
                           index + 1);
            continue;
        }
        close_collapsed_gaps(curves, unreversed, precision);
        if (reversed)
            for (Handle(Geom2d_BSplineCurve) & c : curves) c->Mirror(mirror);
        if (w.IsSame(outer) && outer_curves.empty())
            outer_curves = curves;
        else
            holes.push_back(curves);
    }
    if (!outer_curves.empty() && !loop_is_domain_border(outer_curves, u0, u1, v0, v1)) {
        part->has_outer = 1;
        if ((st = loop_from_curves(outer_curves, &part->outer, err)) != SEM_OK) return st;
    }
    if (!holes.empty()) {
        part->holes = (sem_trim_loop *)calloc(holes.size(), sizeof(sem_trim_loop));
        if (!part->holes) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (const auto &h : holes) {
            st = loop_from_curves(h, &part->holes[part->n_holes], err);
            part->n_holes++;
            if (st != SEM_OK) return st;
        }
    }
    return SEM_OK;
}

/* ---- sem -> Open CASCADE ---- */

void compress_knots(const double *flat, int n, std::vector<double> &knots, std::vector<int> &mults)
{
    for (int i = 0; i < n; ++i) {
        if (!knots.empty() && flat[i] == knots.back())
            mults.back()++;
        else {
            knots.push_back(flat[i]);
            mults.push_back(1);
        }
    }
}

Handle(Geom_BSplineSurface) surface_to_occt(const sem_surface *s)
{
    TColgp_Array2OfPnt poles(1, s->n_u, 1, s->n_v);
    TColStd_Array2OfReal weights(1, s->n_u, 1, s->n_v);
    for (int j = 0; j < s->n_v; ++j)
        for (int i = 0; i < s->n_u; ++i) {
            size_t k = (size_t)i + (size_t)s->n_u * (size_t)j;
            poles(i + 1, j + 1) = gp_Pnt(s->ctrl[3 * k], s->ctrl[3 * k + 1], s->ctrl[3 * k + 2]);
            weights(i + 1, j + 1) = s->weights[k];
        }
    std::vector<double> ku, kv;
    std::vector<int> mu, mv;
    compress_knots(s->knots_u, s->n_u + s->degree_u + 1, ku, mu);
    compress_knots(s->knots_v, s->n_v + s->degree_v + 1, kv, mv);
    TColStd_Array1OfReal aku(1, (int)ku.size()), akv(1, (int)kv.size());
    TColStd_Array1OfInteger amu(1, (int)mu.size()), amv(1, (int)mv.size());
    for (size_t i = 0; i < ku.size(); ++i) aku((int)i + 1) = ku[i], amu((int)i + 1) = mu[i];
    for (size_t i = 0; i < kv.size(); ++i) akv((int)i + 1) = kv[i], amv((int)i + 1) = mv[i];
    return new Geom_BSplineSurface(poles, weights, aku, akv, amu, amv, s->degree_u, s->degree_v);
}

Handle(Geom2d_BSplineCurve) curve_to_occt(const sem_curve *c)
{
    TColgp_Array1OfPnt2d poles(1, c->n_ctrl);
    TColStd_Array1OfReal weights(1, c->n_ctrl);
    for (int i = 0; i < c->n_ctrl; ++i) {
        poles(i + 1) = gp_Pnt2d(c->ctrl[3 * i], c->ctrl[3 * i + 1]);
        weights(i + 1) = c->weights[i];
    }
    std::vector<double> k;
    std::vector<int> m;
    compress_knots(c->knots, c->n_ctrl + c->degree + 1, k, m);
    TColStd_Array1OfReal ak(1, (int)k.size());
    TColStd_Array1OfInteger am(1, (int)m.size());
    for (size_t i = 0; i < k.size(); ++i) ak((int)i + 1) = k[i], am((int)i + 1) = m[i];
    Handle(Geom2d_BSplineCurve) b = new Geom2d_BSplineCurve(poles, weights, ak, am, c->degree);
    if (c->t0 > b->FirstParameter() || c->t1 < b->LastParameter()) b->Segment(c->t0, c->t1);
    return b;
}

/* A wire on the surface from a trim loop, its gaps closed by ShapeFix_Wire. */
TopoDS_Wire wire_to_occt(const sem_trim_loop *loop, const Handle(Geom_BSplineSurface) & surface,
                         const TopoDS_Face &face, double precision)
{
    Handle(ShapeExtend_WireData) data = new ShapeExtend_WireData;
    for (int k = 0; k < loop->n_curves; ++k) {
        Handle(Geom2d_BSplineCurve) c = curve_to_occt(&loop->curves[k]);
        double f = c->FirstParameter(), l = c->LastParameter();
        BRepBuilderAPI_MakeEdge me(c, surface, f, l);
        if (me.IsDone()) {
            TopoDS_Edge e = me.Edge();
            BRepLib::BuildCurves3d(e);
            data->Add(e);
            continue;
        }
        /* a curve whose image is one point: the collapsed edge of a pole, which the loop
         * needs in (u,v); Open CASCADE's form of it is a degenerated edge */
        gp_Pnt a = surface->Value(c->Value(f).X(), c->Value(f).Y());
        gp_Pnt m = surface->Value(c->Value(0.5 * (f + l)).X(), c->Value(0.5 * (f + l)).Y());
        gp_Pnt b = surface->Value(c->Value(l).X(), c->Value(l).Y());
        if (a.Distance(m) > precision || a.Distance(b) > precision) continue;
        BRep_Builder builder;
        TopoDS_Edge e;
        builder.MakeEdge(e);
        builder.UpdateEdge(e, c, surface, TopLoc_Location(), precision);
        builder.Range(e, f, l);
        builder.Degenerated(e, Standard_True);
        TopoDS_Vertex v;
        builder.MakeVertex(v, a, precision);
        builder.Add(e, v.Oriented(TopAbs_FORWARD));
        builder.Add(e, v.Oriented(TopAbs_REVERSED));
        data->Add(e);
    }
    ShapeFix_Wire fix(data->Wire(), face, precision);
    fix.FixReorderMode() = 1;
    fix.FixConnectedMode() = 1;
    fix.ClosedWireMode() = Standard_True;
    fix.Perform();
    return fix.Wire();
}

TopoDS_Face face_from_part(const sem_part *part)
{
    const sem_surface *s = &part->surface;
    Handle(Geom_BSplineSurface) surface = surface_to_occt(s);
    double precision = 1e-7 * sem_surface_net_size(s);
    /* the untrimmed face over the part's domain; trimmed parts replace its outer wire */
    TopoDS_Face whole = BRepBuilderAPI_MakeFace(surface, s->u0, s->u1, s->v0, s->v1, precision).Face();
    if (!part->has_outer && part->n_holes == 0) return whole;
    TopoDS_Face face;
    if (part->has_outer) {
        TopoDS_Wire outer = wire_to_occt(&part->outer, surface, whole, precision);
        BRepBuilderAPI_MakeFace mf(surface, outer, Standard_True);
        face = mf.Face();
    } else {
        face = whole;
    }
    BRep_Builder builder;
    for (int h = 0; h < part->n_holes; ++h)
        builder.Add(face, wire_to_occt(&part->holes[h], surface, whole, precision));
    ShapeFix_Face fix(face);
    fix.FixOrientationMode() = 1;
    fix.Perform();
    return fix.Face();
}

/* Control points of a part: its surface's and its trim curves'. */
long long part_control_points(const sem_part *part)
{
    long long n = (long long)part->surface.n_u * part->surface.n_v;
    for (int c = 0; c < part->outer.n_curves; ++c) n += part->outer.curves[c].n_ctrl;
    for (int h = 0; h < part->n_holes; ++h)
        for (int c = 0; c < part->holes[h].n_curves; ++c) n += part->holes[h].curves[c].n_ctrl;
    return n;
}

sem_status read_step(const char *path, sem_model **out, sem_error *err)
{
    sem_status checked = sem_check_regular_file(path, SEM_MAX_MODEL_FILE_BYTES,
                                                "SEM_MAX_MODEL_FILE_BYTES", err);
    if (checked != SEM_OK) return checked;
    STEPControl_Reader reader;
    if (reader.ReadFile(path) != IFSelect_RetDone)
        return sem_error_set(err, SEM_ERR_PARSE, "%s: not a STEP file Open CASCADE can read", path);
    /* the file's length unit: keep the geometry in it */
    TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
    reader.FileUnits(lengths, angles, solid_angles);
    const unit_name *unit = lengths.Length() > 0 ? unit_by_step_name(lengths.Value(1).ToCString())
                                                 : nullptr;
    if (!unit) unit = &UNITS[0]; /* STEP's default is the millimetre */
    reader.SetSystemLengthUnit(unit->mm);
    if (reader.TransferRoots() <= 0 || reader.NbShapes() == 0)
        return sem_error_set(err, SEM_ERR_PARSE, "%s: no shape could be read from the file", path);
    TopoDS_Shape shape = reader.OneShape();

    sem_model *m = sem_model_create();
    if (!m) return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
    snprintf(m->units, sizeof m->units, "%s", unit->ours);
    m->unit_to_meter = unit->mm / 1000.0;
    int index = 0;
    long long built = 0; /* control points of the parts so far (SEM_MAX_MODEL_CONTROL_POINTS) */
    for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next(), ++index) {
        /* an assembly may place one shape many times: its faces count every time */
        if (m->n_parts >= SEM_MAX_PARTS) {
            sem_model_destroy(m);
            return sem_error_set(err, SEM_ERR_INVALID, "%s: the model would have more than %d parts "
                                                       "(limit SEM_MAX_PARTS)",
                                 path, SEM_MAX_PARTS);
        }
        sem_part part;
        memset(&part, 0, sizeof part);
        sem_error perr;
        sem_status st;
        try {
            st = part_from_face(TopoDS::Face(ex.Current()), index, &part, m, &perr);
        } catch (const Standard_Failure &e) {
            /* one face Open CASCADE cannot convert (corpus occt_abc_0_13: an empty array in
             * its NURBS conversion) costs that face, not the file */
            sem_part_free(&part);
            memset(&part, 0, sizeof part);
            st = sem_error_set(&perr, SEM_ERR_UNSUPPORTED, "Open CASCADE: %s", e.GetMessageString());
        }
        if (st == SEM_OK) {
            /* loops made usable (geometry/trim_fix.h): a cylinder's band whose pcurves start
             * off the converted surface's seam (corpus nist_ctc_05, chrono_assembly lost a
             * strip of 0.6 %), gaps within the edges' own tolerance */
            sem_loop_fix fix;
            memset(&fix, 0, sizeof fix);
            for (TopExp_Explorer e(ex.Current(), TopAbs_EDGE); e.More(); e.Next())
                fix.bridge = std::max(fix.bridge, BRep_Tool::Tolerance(TopoDS::Edge(e.Current())));
            if (sem_part_fix_loops(&part, &fix) != SEM_OK) {
                sem_part_free(&part);
                sem_model_destroy(m);
                return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
            }
            if (fix.widest_gap > 0)
                sem_model_warn(m, "face %d: a gap of %.3g between trim curves is bridged (allowed "
                                  "%.3g: the edges' tolerance or 1e-4 of the surface)",
                               index + 1, fix.widest_gap, fix.gap_limit);
            if (fix.outer_dropped || fix.holes_dropped)
                sem_model_warn(m, "face %d: a trim loop does not close (a gap wider than %.3g); "
                                  "left out", index + 1, fix.gap_limit);
            if (fix.wound)
                sem_model_warn(m, "face %d: the trim loops wind around the closed surface and "
                                  "cannot share one period of it; kept as they are", index + 1);
            sem_error verr;
            if (sem_part_validate_trims(&part, &verr) != SEM_OK) {
                sem_model_warn(m, "face %d: %s; kept untrimmed", index + 1, verr.message);
                sem_part_untrim(&part);
            }
            built += part_control_points(&part);
            if (built > SEM_MAX_MODEL_CONTROL_POINTS) {
                sem_part_free(&part);
                sem_model_destroy(m);
                return sem_error_set(err, SEM_ERR_INVALID, "%s: the model would have more than %d "
                                                           "control points (surfaces and trim "
                                                           "curves; limit "
                                                           "SEM_MAX_MODEL_CONTROL_POINTS)",
                                     path, SEM_MAX_MODEL_CONTROL_POINTS);
            }
            st = sem_model_take_part(m, &part, &perr);
        }
        if (st != SEM_OK) {
            sem_part_free(&part);
            if (st == SEM_ERR_NOMEM) {
                sem_model_destroy(m);
                return sem_error_set(err, st, "%s: %s", path, perr.message);
            }
            sem_model_warn(m, "face %d skipped: %s", index + 1, perr.message);
        }
    }
    if (m->n_parts == 0) {
        sem_model_destroy(m);
        return sem_error_set(err, SEM_ERR_PARSE, "%s: the file has no faces", path);
    }
    sem_error lerr;
    if (sem_model_check_limits(m, &lerr) != SEM_OK) {
        sem_model_destroy(m);
        return sem_error_set(err, lerr.status, "%s: %s", path, lerr.message);
    }
    *out = m;
    return SEM_OK;
}

sem_status write_step(const sem_model *model, const char *path, sem_error *err)
{
    if (model->n_parts == 0)
        return sem_error_set(err, SEM_ERR_INVALID, "%s: the model has no parts", path);
    const unit_name *unit = unit_of_model(model);
    if (!unit) unit = &UNITS[1]; /* unknown: metres, as sem takes lengths */
    TopoDS_Compound compound;
    BRep_Builder builder;
    builder.MakeCompound(compound);
    for (int i = 0; i < model->n_parts; ++i) builder.Add(compound, face_from_part(&model->parts[i]));

    STEPControl_Writer writer;
    static_setting unit_setting("write.step.unit", unit->occt);
    static_setting schema_setting("write.step.schema", "AP214IS");
    writer.Model()->SetLocalLengthUnit(unit->mm); /* the shape is in the model's unit */
    writer.Model()->SetWriteLengthUnit(unit->mm);
    if (writer.Transfer(compound, STEPControl_AsIs) != IFSelect_RetDone)
        return sem_error_set(err, SEM_ERR_INVALID, "%s: Open CASCADE could not translate the model",
                             path);
    /* all or nothing, as every writer (io/atomic_file.h): Open CASCADE writes the
     * temporary file by its name, the commit syncs and renames it */
    sem_atomic_file f;
    sem_status st = sem_atomic_open(&f, path, err);
    if (st != SEM_OK) return st;
    if (writer.Write(f.tmp_path) != IFSelect_RetDone) {
        sem_atomic_abort(&f);
        return sem_error_set(err, SEM_ERR_IO, "%s: cannot write the STEP file", path);
    }
    st = sem_atomic_commit(&f, err);
    if (st != SEM_OK) return st;
    return SEM_OK;
}

} // namespace

extern "C" sem_status sem_step_read(const char *path, sem_model **out, sem_error *err)
{
    if (out) *out = nullptr;
    if (!path || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_step_read: NULL argument");
    std::lock_guard<std::mutex> lock(occt_mutex);
    quiet_messenger quiet;
    try {
        return read_step(path, out, err);
    } catch (const Standard_Failure &e) {
        return sem_error_set(err, SEM_ERR_PARSE, "%s: Open CASCADE: %s", path, e.GetMessageString());
    } catch (const std::bad_alloc &) {
        return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
    }
}

extern "C" sem_status sem_step_write(const sem_model *model, const char *path, sem_error *err)
{
    if (!model || !path) return sem_error_set(err, SEM_ERR_INVALID, "sem_step_write: NULL argument");
    std::lock_guard<std::mutex> lock(occt_mutex);
    quiet_messenger quiet;
    try {
        return write_step(model, path, err);
    } catch (const Standard_Failure &e) {
        return sem_error_set(err, SEM_ERR_INVALID, "%s: Open CASCADE: %s", path, e.GetMessageString());
    } catch (const std::bad_alloc &) {
        return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
    }
}

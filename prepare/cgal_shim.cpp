/*
 * prepare/cgal_shim.cpp -- decimation, isotropic remeshing and closest points
 * with CGAL, behind the plain-C interface of cgal_shim.h. The only file that
 * includes CGAL (its compile unit is heavy: keep it to these three calls).
 *
 * All three build a CGAL structure from the C arrays, run one CGAL algorithm
 * and copy the result back to malloc'd arrays. Kernel: Epick (exact
 * predicates, double constructions) as CGAL recommends for both PMP and SMS.
 * Seams are an edge property "e:seam" of the Surface_mesh; CGAL keeps it up to
 * date through splits (isotropic_remeshing marks sub-edges of a constrained
 * edge constrained), so the seams come back as edges of the output.
 *
 * Failure: every exception (std::bad_alloc, CGAL's, ours) is caught here and
 * becomes PZ_ERR_NOMEM or PZ_ERR_INTERNAL with a one-line message; *out is
 * left empty. Memory: a Surface_mesh is ~ 250 bytes per face; the AABB tree
 * ~ 150 bytes per triangle.
 *
 * Threads: closest points build 2 AABB trees in parallel for big surfaces and
 * split the queries over the cores (std::thread); every thread writes its own
 * slice of the output, so the results do not depend on the threads.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/cgal_shim.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Constrained_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Edge_length_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Midpoint_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <stdexcept>
#include <thread>
#include <vector>

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Surface;
typedef Surface::Vertex_index Vertex;
typedef Surface::Edge_index Edge;
typedef Surface::Property_map<Edge, bool> EdgeFlags;

/* The Surface_mesh of a C surface, with its seams in the "e:seam" property. */
void build_surface(const pz_cgal_surface *in, Surface &surface, EdgeFlags &seam)
{
    surface.reserve(in->vertex_count, 3 * in->face_count / 2 + in->vertex_count, in->face_count);
    std::vector<Vertex> vertices((size_t)in->vertex_count);
    for (int32_t v = 0; v < in->vertex_count; ++v) {
        const double *p = in->positions + 3 * (size_t)v;
        vertices[(size_t)v] = surface.add_vertex(Point(p[0], p[1], p[2]));
    }
    for (int32_t f = 0; f < in->face_count; ++f) {
        const int32_t *c = in->faces + 3 * (size_t)f;
        if (surface.add_face(vertices[c[0]], vertices[c[1]], vertices[c[2]]) == Surface::null_face())
            throw std::runtime_error("face " + std::to_string(f) + " is not manifold or not oriented");
    }
    seam = surface.add_property_map<Edge, bool>("e:seam", false).first;
    for (int32_t e = 0; e < in->edge_count; ++e) {
        auto h = CGAL::halfedge(vertices[in->edges[2 * e]], vertices[in->edges[2 * e + 1]], surface);
        if (h.second)
            seam[surface.edge(h.first)] = true;
    }
}

template <typename T> T *allocate(size_t count)
{
    void *data = std::malloc(count * sizeof(T) + 1);
    if (!data)
        throw std::bad_alloc();
    return static_cast<T *>(data);
}

/* Copies a (garbage-collected) Surface_mesh and its seam edges back to C arrays. */
void export_surface(Surface &surface, const EdgeFlags &seam, pz_cgal_surface *out)
{
    surface.collect_garbage();
    pz_cgal_surface result = {};
    try {
        result.vertex_count = (int32_t)surface.number_of_vertices();
        result.face_count = (int32_t)surface.number_of_faces();
        result.positions = allocate<double>(3 * (size_t)result.vertex_count);
        result.faces = allocate<int32_t>(3 * (size_t)result.face_count);
        for (Vertex v : surface.vertices()) {
            const Point &p = surface.point(v);
            for (int k = 0; k < 3; ++k)
                result.positions[3 * (size_t)v.idx() + k] = p[k];
        }
        for (auto f : surface.faces()) {
            int k = 0;
            for (Vertex v : CGAL::vertices_around_face(surface.halfedge(f), surface))
                result.faces[3 * (size_t)f.idx() + k++] = (int32_t)v.idx();
        }
        size_t seam_count = 0;
        for (Edge e : surface.edges())
            seam_count += seam[e];
        result.edges = allocate<int32_t>(2 * seam_count);
        for (Edge e : surface.edges())
            if (seam[e]) {
                result.edges[2 * result.edge_count] = (int32_t)surface.source(surface.halfedge(e)).idx();
                result.edges[2 * result.edge_count + 1] = (int32_t)surface.target(surface.halfedge(e)).idx();
                ++result.edge_count;
            }
    } catch (...) {
        pz_cgal_surface_clear(&result);
        throw;
    }
    *out = result;
}

/* Turns the exception in flight into a status and a one-line message. */
pz_status report_exception(const char *what_failed, pz_ctx *ctx)
{
    try {
        throw;
    } catch (const std::bad_alloc &) {
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", what_failed);
    } catch (const std::exception &error) {
        return pz_error(ctx, PZ_ERR_INTERNAL, "%s: %s", what_failed, error.what());
    } catch (...) {
        return pz_error(ctx, PZ_ERR_INTERNAL, "%s: unknown failure in CGAL", what_failed);
    }
}

} // namespace

extern "C" void pz_cgal_surface_clear(pz_cgal_surface *surface)
{
    std::free(surface->positions);
    std::free(surface->faces);
    std::free(surface->edges);
    std::free(surface->locked);
    std::memset(surface, 0, sizeof *surface);
}

extern "C" pz_status pz_cgal_decimate(const pz_cgal_surface *in, int32_t target_faces, pz_cgal_surface *out,
                                      pz_ctx *ctx)
{
    namespace SMS = CGAL::Surface_mesh_simplification;
    std::memset(out, 0, sizeof *out);
    try {
        Surface surface;
        EdgeFlags seam;
        build_surface(in, surface, seam);
        /* Locked = seam or outline: neither collapses, and Constrained_placement
         * keeps their vertices where they are. */
        EdgeFlags locked = surface.add_property_map<Edge, bool>("e:locked", false).first;
        for (Edge e : surface.edges())
            locked[e] = seam[e] || surface.is_border(e);
        /* Shortest edge first with midpoint placement: several times faster than
         * Lindstrom-Turk, and the remeshing that follows fixes the shapes. */
        SMS::Count_stop_predicate<Surface> stop((size_t)target_faces * 3 / 2);
        SMS::Constrained_placement<SMS::Midpoint_placement<Surface>, EdgeFlags> placement(locked);
        SMS::edge_collapse(surface, stop,
                           CGAL::parameters::edge_is_constrained_map(locked)
                               .get_cost(SMS::Edge_length_cost<Surface>())
                               .get_placement(placement));
        export_surface(surface, seam, out);
        return PZ_OK;
    } catch (...) {
        return report_exception("decimation", ctx);
    }
}

extern "C" pz_status pz_cgal_remesh(const pz_cgal_surface *in, double target_edge, int iterations,
                                    pz_cgal_surface *out, pz_ctx *ctx)
{
    std::memset(out, 0, sizeof *out);
    try {
        Surface surface;
        EdgeFlags seam;
        build_surface(in, surface, seam);
        /* Corners of the outline and of the seams: collapsing them would cut the corner off. */
        auto locked = surface.add_property_map<Vertex, bool>("v:locked", false).first;
        for (int32_t i = 0; i < in->locked_count; ++i)
            locked[Vertex((Surface::size_type)in->locked[i])] = true;
        CGAL::Polygon_mesh_processing::isotropic_remeshing(
            surface.faces(), target_edge, surface,
            CGAL::parameters::number_of_iterations(iterations)
                .edge_is_constrained_map(seam)
                .vertex_is_constrained_map(locked)
                .protect_constraints(false));
        export_surface(surface, seam, out);
        return PZ_OK;
    } catch (...) {
        return report_exception("remeshing", ctx);
    }
}

namespace {

/*
 * Runs job(0) .. job(count - 1) on count threads (job 0 on the caller's) and
 * rethrows the first exception once all have finished. Each job writes only
 * its own slice, so results do not depend on the threads' timing.
 */
template <typename Job> void run_parallel(size_t count, const Job &job)
{
    std::vector<std::exception_ptr> failures(count);
    std::vector<std::thread> threads;
    auto guarded = [&](size_t i) {
        try {
            job(i);
        } catch (...) {
            failures[i] = std::current_exception();
        }
    };
    try {
        for (size_t i = 1; i < count; ++i)
            threads.emplace_back(guarded, i);
    } catch (...) {
        for (std::thread &thread : threads)
            thread.join();
        throw;
    }
    guarded(0);
    for (std::thread &thread : threads)
        thread.join();
    for (const std::exception_ptr &failure : failures)
        if (failure)
            std::rethrow_exception(failure);
}

/* Threads for the queries: the cores, at most 8; one for small jobs. */
size_t query_threads(int32_t query_count)
{
    size_t cores = std::thread::hardware_concurrency();
    if (query_count < 20000 || cores < 2)
        return 1;
    return cores < 8 ? cores : 8;
}

} // namespace

/*
 * Building the AABB tree is sequential and takes most of the time for a big
 * surface (1M triangles: ~1 s), so above TREE_SPLIT_FACES the triangles are
 * split into TREE_COUNT slices, one tree each, built in parallel, and every
 * query takes the closest of the trees' answers (the lower slice on a tie).
 * TREE_COUNT is fixed, not the core count, so the face chosen on a tie (a
 * point closest to an edge) is the same on every machine.
 */
#define TREE_SPLIT_FACES 200000
#define TREE_COUNT 2

extern "C" pz_status pz_cgal_closest_points(const double *positions, int32_t vertex_count, const int32_t *faces,
                                            int32_t face_count, const double *queries, int32_t query_count,
                                            double *closest, int32_t *face, pz_ctx *ctx)
{
    typedef std::vector<Kernel::Triangle_3>::const_iterator Iterator;
    typedef CGAL::AABB_triangle_primitive<Kernel, Iterator> Primitive;
    typedef CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>> Tree;
    (void)vertex_count;
    try {
        if (face_count <= 0)
            throw std::runtime_error("no faces to project on");
        std::vector<Kernel::Triangle_3> triangles;
        triangles.reserve((size_t)face_count);
        for (int32_t f = 0; f < face_count; ++f) {
            const double *a = positions + 3 * (size_t)faces[3 * f], *b = positions + 3 * (size_t)faces[3 * f + 1],
                         *c = positions + 3 * (size_t)faces[3 * f + 2];
            triangles.emplace_back(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]), Point(c[0], c[1], c[2]));
        }
        size_t tree_count = face_count >= TREE_SPLIT_FACES ? TREE_COUNT : 1;
        std::vector<std::unique_ptr<Tree>> trees(tree_count);
        /* Built and accelerated before any query: queries on a built tree are read-only. */
        run_parallel(tree_count, [&](size_t t) {
            trees[t].reset(new Tree(triangles.cbegin() + (ptrdiff_t)(triangles.size() * t / tree_count),
                                    triangles.cbegin() + (ptrdiff_t)(triangles.size() * (t + 1) / tree_count)));
            trees[t]->build();
            trees[t]->accelerate_distance_queries();
        });
        size_t threads = query_threads(query_count);
        run_parallel(threads, [&](size_t t) {
            int32_t first = (int32_t)((size_t)query_count * t / threads);
            int32_t last = (int32_t)((size_t)query_count * (t + 1) / threads);
            for (int32_t q = first; q < last; ++q) {
                const double *p = queries + 3 * (size_t)q;
                Point point(p[0], p[1], p[2]);
                double best = INFINITY;
                for (const std::unique_ptr<Tree> &tree : trees) {
                    auto hit = tree->closest_point_and_primitive(point);
                    double d = CGAL::squared_distance(point, hit.first);
                    if (d < best) {
                        best = d;
                        for (int k = 0; k < 3; ++k)
                            closest[3 * (size_t)q + k] = hit.first[k];
                        face[q] = (int32_t)(hit.second - triangles.cbegin());
                    }
                }
            }
        });
        return PZ_OK;
    } catch (...) {
        return report_exception("closest points", ctx);
    }
}

/*
 * param/textile_local.c -- the local step of the textile parameterization:
 * per face the stretch (Eqs. 2-5) and rigidity (Eq. 6) terms and their share
 * of the global step's systems, per seam and dart the reflection (Eqs. 7-8),
 * dart symmetry (Eq. 9) and equal-length targets; and the grain alignment
 * that turns every panel so its warp follows the grain. The design:
 * param/textile_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/textile_internal.h"

#include <math.h>
#include <omp.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Local step                                                                */
/* ------------------------------------------------------------------------ */

/*
 * Face f's share of coordinate k's system in the global step: the rigid
 * edge targets t (Eq. 6) and the stretch term (docs/param.md, "Consistent
 * stretch steps"). Eq. 10 evaluates w A (s_k - 1)^2, and with the other
 * coordinate fixed s_k of the new triangle is exactly s_k / a, a = c_k .
 * x_new (c_k: the old triangle's hat gradients), so the face's term is
 * w A (s_k / a - 1)^2. The paper's row w A (s_k - a)^2 has the right
 * minimizer (a = s_k) but its slope at a = 1 is 1 / s_k of the true one, so
 * the local/global map stops where the weighted slopes balance, not at a
 * stationary point of Eq. 10: near that fixed point every full step raised
 * the energy and was backtracked. Weighting the row by s_k makes the slopes
 * equal (the minimizer stays a = s_k). The other coordinate's term depends
 * on coordinate k through the shear, d s_o = -(J_1 . J_2 / s_o) dT_ko (T: the
 * new triangle in the old one's frame, T_ko = c_o . x_k,new): `cross` is its
 * slope, `cross_weight` its Gauss-Newton curvature w A (J_1 . J_2 / s_o)^2
 * along c_o (without it the force, scaled up by the strain goal's weights,
 * threw steps far off: most steps were backtracked on the shared garments).
 * Far from the goal (s_k outside [1/STRETCH_STEP_RANGE, STRETCH_STEP_RANGE];
 * the LSCM start of the face scan has faces squeezed 1000x) the row asks for
 * at most that factor per step (a trust region) and the shear terms are
 * left out.
 */
#define STRETCH_STEP_RANGE 2.0

/* Per coordinate k, over the poses used: the mean of s_k, of s_k^2, of
 * (s_k - 1) J_1 . J_2 / s_k (the shear slope) and of (J_1 . J_2 / s_k)^2. */
typedef struct stretch_figures {
    double s[2], second[2], slope[2], curvature[2];
} stretch_figures;

static void face_system(const double c[2][3], const stretch_figures *figures, const double t[3][2],
                        double stretch_weight, double w_rigid, int k, face_terms *terms)
{
    static const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    int o = 1 - k;
    const double *s = figures->s;
    double low = 1 / STRETCH_STEP_RANGE;
    double clamped = s[k] > STRETCH_STEP_RANGE ? STRETCH_STEP_RANGE : s[k] < low ? low : s[k];
    int near = clamped == s[k] && s[o] <= STRETCH_STEP_RANGE && s[o] >= low;
    double row_weight = stretch_weight * clamped;
    /* With poses the row's slope is the mean of the poses' slopes:
     * sum_p s_p (s_p - 1) = P s (s + var / s - 1); var = 0 for one pose. */
    double variance = figures->second[k] - s[k] * s[k]; /* 0 with one pose: no division then */
    double target = near ? (variance != 0 ? s[k] + variance / s[k] : s[k]) : clamped;
    double cross = near ? stretch_weight * figures->slope[o] : 0;
    double cross_weight = near ? stretch_weight * figures->curvature[o] : 0;
    for (int e = 0; e < 6; ++e) {
        int a = pair[e][0], b = pair[e][1];
        terms->value[k][e] = row_weight * c[k][a] * c[k][b] + cross_weight * c[o][a] * c[o][b] +
                             (a == b ? 2 * w_rigid : -w_rigid);
    }
    for (int a = 0; a < 3; ++a)
        terms->rhs[k][a] = row_weight * target * c[k][a] + cross * c[o][a];
    for (int e = 0; e < 3; ++e) {
        terms->rhs[k][(e + 1) % 3] += w_rigid * t[e][k];
        terms->rhs[k][e] -= w_rigid * t[e][k];
    }
}

/* Stretch coefficients and targets, rigid edge targets of face f, and from
 * them its share of the global step (face_system); returns its energy at
 * the current uv. */
static double local_face(const textile_state *state, int32_t f, const double *uv)
{
    const int32_t *face = state->pattern->mesh->faces + 3 * f;
    double q[3][2], c[2][3];
    for (int i = 0; i < 3; ++i) {
        q[i][0] = uv[2 * face[i]];
        q[i][1] = uv[2 * face[i] + 1];
    }
    double twice_area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
    double area_3d = state->areas[f];
    /* A collapsed 2D triangle has no barycentric gradients, and a flipped
     * one would be held mirrored by its stretch rows (c . u = 1 whatever the
     * orientation): their stretch rows are dropped for this iteration and the
     * rotation-only rigidity term alone turns them back. */
    int stretch = twice_area > 1e-12 * area_3d && area_3d > 0;
    /* One division per face: this loop runs once per evaluation over every face, and divisions were
     * most of its cost (about 28 per face before issue 17). */
    double inverse_area = stretch ? 1 / twice_area : 0;
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        c[0][i] = (q[j][1] - q[k][1]) * inverse_area;
        c[1][i] = (q[k][0] - q[j][0]) * inverse_area;
    }
    double qe[3][2];
    for (int e = 0; e < 3; ++e) {
        int j = (e + 1) % 3;
        qe[e][0] = q[j][0] - q[e][0];
        qe[e][1] = q[j][1] - q[e][1];
    }
    double image[2] = {0, 0}; /* c_k . q: 1 up to rounding (c_k are the hat functions' k-derivatives) */
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 3; ++i)
            image[k] += c[k][i] * q[i][k];
    stretch_figures figures = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
    double t[3][2] = {{0, 0}, {0, 0}, {0, 0}}, stretch_sum[2] = {0, 0}, rigid_sum = 0;
    int32_t poses = state->pose_total;
    for (int32_t p = 0; p < poses; ++p) {
        const double *frame = state->frames + ((size_t)f * poses + p) * 3;
        double P[3][2] = {{0, 0}, {frame[0], 0}, {frame[1], frame[2]}};
        double thread[2][2], length[2]; /* J_k in the 3D frame, |J_k| */
        for (int k = 0; k < 2; ++k) {
            thread[k][0] = thread[k][1] = 0;
            for (int i = 0; i < 3; ++i) {
                thread[k][0] += c[k][i] * P[i][0];
                thread[k][1] += c[k][i] * P[i][1];
            }
            length[k] = sqrt(thread[k][0] * thread[k][0] + thread[k][1] * thread[k][1]);
        }
        double threads_dot = thread[0][0] * thread[1][0] + thread[0][1] * thread[1][1];
        for (int k = 0; k < 2; ++k) {
            double shear = length[k] > 0 ? threads_dot / length[k] : 0;
            figures.s[k] += length[k];
            figures.second[k] += length[k] * length[k];
            figures.slope[k] += (length[k] - 1) * shear;
            figures.curvature[k] += shear * shear;
            stretch_sum[k] += (length[k] - image[k]) * (length[k] - image[k]);
        }
        double pe[3][2], s00 = 0, s01 = 0, s10 = 0, s11 = 0;
        for (int e = 0; e < 3; ++e) {
            int j = (e + 1) % 3;
            pe[e][0] = P[j][0] - P[e][0];
            pe[e][1] = P[j][1] - P[e][1];
            s00 += qe[e][0] * pe[e][0];
            s01 += qe[e][0] * pe[e][1];
            s10 += qe[e][1] * pe[e][0];
            s11 += qe[e][1] * pe[e][1];
        }
        /* The rotation maximizing tr(R^T S), S = sum q_e p_e^T. */
        double cs = s00 + s11, sn = s10 - s01, norm = sqrt(cs * cs + sn * sn);
        if (norm > 0) {
            double inverse_norm = 1 / norm;
            cs *= inverse_norm;
            sn *= inverse_norm;
        } else {
            cs = 1;
            sn = 0;
        }
        for (int e = 0; e < 3; ++e) {
            double target[2] = {cs * pe[e][0] - sn * pe[e][1], sn * pe[e][0] + cs * pe[e][1]};
            for (int k = 0; k < 2; ++k) {
                t[e][k] += target[k];
                rigid_sum += (qe[e][k] - target[k]) * (qe[e][k] - target[k]);
            }
        }
    }
    double energy = 0, stretch_weight = state->w_stretch * area_3d * (state->stretch_boost ? state->stretch_boost[f] : 1);
    double worst_strain = 0;
    if (poses > 1) /* the means over the poses (one pose: the sums are the means) */
        for (int k = 0; k < 2; ++k) {
            figures.s[k] /= poses;
            figures.second[k] /= poses;
            figures.slope[k] /= poses;
            figures.curvature[k] /= poses;
            stretch_sum[k] /= poses;
            for (int e = 0; e < 3; ++e)
                t[e][k] /= poses;
        }
    for (int k = 0; k < 2; ++k)
        if (stretch) {
            energy += stretch_weight * stretch_sum[k];
            /* s_k - 1 is the strain |J_k| - 1 of docs/metrics.md (the mean over poses). */
            worst_strain = fmax(worst_strain, fabs(figures.s[k] - 1));
        }
    if (state->face_strain)
        state->face_strain[f] = worst_strain;
    energy += state->w_rigid * (poses > 1 ? rigid_sum / poses : rigid_sum);
    for (int k = 0; k < 2; ++k)
        face_system(c, &figures, t, stretch_weight, state->w_rigid, k, &state->terms[f]);
    state->face_energy[f] = energy;
    state->face_flipped[f] = !(twice_area > 0);
    return energy;
}

/* Adds weight * |x - target|^2 for one vertex; returns the energy. */
static double pull(textile_state *state, int32_t v, double weight, const double target[2], const double *uv)
{
    state->pull_weight[v] += weight;
    state->pull_target[2 * v] += weight * target[0];
    state->pull_target[2 * v + 1] += weight * target[1];
    double du = uv[2 * v] - target[0], dv = uv[2 * v + 1] - target[1];
    state->panel_pull[state->vertex_panel[v]] += weight * (du * du + dv * dv);
    return weight * (du * du + dv * dv);
}

/* Eqs. 7-8: best-fit reflection M of side a onto side b (textile_fit_reflection),
 * midpoint targets for both sides. */
static double seam_targets(textile_state *state, const pz_seam *seam, const double *uv)
{
    int32_t n = seam->pair_count;
    if (n < 2 || state->w_seam <= 0)
        return 0;
    double c, s, t[2];
    textile_fit_reflection(seam, uv, &c, &s, t);
    double energy = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * seam->side_a[i], *q = uv + 2 * seam->side_b[i];
        double mp[2] = {c * p[0] + s * p[1] + t[0], s * p[0] - c * p[1] + t[1]};
        double qt[2] = {q[0] - t[0], q[1] - t[1]};
        double mq[2] = {c * qt[0] + s * qt[1], s * qt[0] - c * qt[1]}; /* M^-1 q = R (q - t) */
        double target_a[2] = {(p[0] + mq[0]) / 2, (p[1] + mq[1]) / 2};
        double target_b[2] = {(q[0] + mp[0]) / 2, (q[1] + mp[1]) / 2};
        energy += pull(state, seam->side_a[i], state->w_seam, target_a, uv);
        energy += pull(state, seam->side_b[i], state->w_seam, target_b, uv);
    }
    return energy;
}

/*
 * Equal lengths of facing segments (build_segments), pairs g = first,
 * first + 2, ...: for e_a = a_{i+1} - a_i and e_b = b_{i+1} - b_i the targets
 * keep each segment's direction and give both the mean length
 * L = (|e_a| + |e_b|) / 2. Those are the minimizers of |e_a - L d_a|^2 +
 * |e_b - L d_b|^2 over unit d_a, d_b and L, so the term is
 * w (|e_a| - |e_b|)^2 / 2 and the local/global step stays a majorization,
 * like Procrustes for the rigidity term. Matching segment by segment (not
 * only the totals) keeps facing notches together.
 */
static double segment_length_targets(textile_state *state, int32_t first, int32_t pairs, const double *uv,
                                     double side_length[2])
{
    double energy = 0;
    side_length[0] = side_length[1] = 0;
    for (int32_t g = first; g < first + 2 * pairs; g += 2) {
        double w = state->segment_weight[g];
        double length[2], e[2][2];
        for (int side = 0; side < 2; ++side) {
            const int32_t *ends = state->segment_ends + 2 * (g + side);
            e[side][0] = uv[2 * ends[1]] - uv[2 * ends[0]];
            e[side][1] = uv[2 * ends[1] + 1] - uv[2 * ends[0] + 1];
            length[side] = sqrt(e[side][0] * e[side][0] + e[side][1] * e[side][1]);
        }
        double mean = (length[0] + length[1]) / 2;
        side_length[0] += length[0];
        side_length[1] += length[1];
        for (int side = 0; side < 2; ++side) {
            const int32_t *ends = state->segment_ends + 2 * (g + side);
            double *target = state->segment_target + 2 * (g + side);
            double dx = length[side] > 0 ? e[side][0] / length[side] : 1;
            double dy = length[side] > 0 ? e[side][1] / length[side] : 0;
            double scale = ends[0] == ends[1] ? 0 : mean; /* a repeated vertex: no segment (global step skips it) */
            target[0] = scale * dx;
            target[1] = scale * dy;
            double rx = e[side][0] - target[0], ry = e[side][1] - target[1];
            double term = w * (rx * rx + ry * ry);
            state->panel_pull[state->vertex_panel[ends[0]]] += term;
            energy += term;
        }
    }
    return energy;
}

/* Eq. 9: axis through the tip fitting the leg midpoints; targets average each
 * leg point with its partner mirrored about that axis. */
static double dart_targets(textile_state *state, const pz_dart *dart, const double *uv)
{
    int32_t n = dart->pair_count;
    if (n < 1 || state->w_dart <= 0)
        return 0;
    const double *tip = uv + 2 * dart->tip;
    double c00 = 0, c01 = 0, c11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * dart->leg_a[i], *q = uv + 2 * dart->leg_b[i];
        double rx = (p[0] + q[0]) / 2 - tip[0], ry = (p[1] + q[1]) / 2 - tip[1];
        c00 += rx * rx;
        c01 += rx * ry;
        c11 += ry * ry;
    }
    if (c00 + c11 <= 0)
        return 0;
    double angle = 0.5 * atan2(2 * c01, c00 - c11); /* principal direction */
    double dx = cos(angle), dy = sin(angle);
    double m00 = 2 * dx * dx - 1, m01 = 2 * dx * dy, m11 = 2 * dy * dy - 1;
    double energy = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * dart->leg_a[i], *q = uv + 2 * dart->leg_b[i];
        double px = p[0] - tip[0], py = p[1] - tip[1], qx = q[0] - tip[0], qy = q[1] - tip[1];
        double mirrored_p[2] = {tip[0] + m00 * px + m01 * py, tip[1] + m01 * px + m11 * py};
        double mirrored_q[2] = {tip[0] + m00 * qx + m01 * qy, tip[1] + m01 * qx + m11 * qy};
        double target_a[2] = {(p[0] + mirrored_q[0]) / 2, (p[1] + mirrored_q[1]) / 2};
        double target_b[2] = {(q[0] + mirrored_p[0]) / 2, (q[1] + mirrored_p[1]) / 2};
        energy += pull(state, dart->leg_a[i], state->w_dart, target_a, uv);
        energy += pull(state, dart->leg_b[i], state->w_dart, target_b, uv);
    }
    return energy;
}

static void record_mismatch(textile_state *state, int32_t curve, const double sides[2])
{
    if (state->curve_mismatch && state->curve_length_3d[curve] > 0)
        state->curve_mismatch[curve] = fabs(sides[0] - sides[1]) / state->curve_length_3d[curve];
}

/* The whole local step; returns E_textile (Eq. 10) at the current uv. */
double textile_local_step(textile_state *state, const double *uv)
{
    const pz_pattern *pattern = state->pattern;
    int32_t nf = pattern->mesh->face_count;
    double block_energy[SUM_BLOCKS], energy = 0;
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->parallel)
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        double sum = 0;
        for (int32_t f = block_start(0, nf, block); f < block_start(0, nf, block + 1); ++f)
            sum += local_face(state, f, uv);
        block_energy[block] = sum;
    }
    for (int block = 0; block < SUM_BLOCKS; ++block)
        energy += block_energy[block];
    /* Seams and darts touch few vertices: serial. */
    memset(state->pull_weight, 0, (size_t)pattern->mesh->vertex_count * sizeof(double));
    memset(state->pull_target, 0, (size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    memset(state->panel_pull, 0, (size_t)pattern->panel_count * sizeof(double));
    double sides[2];
    for (int32_t s = 0; s < pattern->seam_count && !state->seams_open; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        if (state->seam_segment_base[s] >= 0) {
            energy += segment_length_targets(state, state->seam_segment_base[s], seam->pair_count - 1, uv, sides);
            record_mismatch(state, s, sides);
        }
        if (!state->seam_length_only[s])
            energy += seam_targets(state, seam, uv);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        if (state->dart_segment_base[d] >= 0) {
            energy += segment_length_targets(state, state->dart_segment_base[d], dart->pair_count, uv, sides);
            record_mismatch(state, pattern->seam_count + d, sides);
        }
        if (!state->dart_length_only[d])
            energy += dart_targets(state, dart, uv);
    }
    return energy;
}

/*
 * The angle that turns panel p's area-weighted projected grain onto +v: the
 * computation of pz_param_grain_angle (lscm.c) with the rest frames and the
 * grain in each frame precomputed at setup. *norm: the length of the
 * weighted sum (0 when the angle is left at 0).
 */
static double panel_grain_angle(const textile_state *state, int32_t panel, const double *uv, double *norm)
{
    const pz_mesh *mesh = state->pattern->mesh;
    double glen = sqrt(dot3(state->grain, state->grain));
    int32_t first = state->offsets[panel], count = state->offsets[panel + 1] - first;
    double block_sums[SUM_BLOCKS][3]; /* sum_u, sum_v, area_sum */
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        double sum_u = 0, sum_v = 0, area_sum = 0;
        for (int32_t i = block_start(first, count, block); i < block_start(first, count, block + 1); ++i) {
            int32_t f = state->order[i];
            const int32_t *face = mesh->faces + 3 * f;
            const double *frame = state->frames + (size_t)f * state->pose_total * 3;
            double area = state->areas[f];
            if (area <= 0)
                continue;
            area_sum += area;
            double a = state->grain_local[2 * f] / glen, b = state->grain_local[2 * f + 1] / glen;
            double projected = sqrt(a * a + b * b);
            if (projected < 1e-9)
                continue;
            const double *q0 = uv + 2 * face[0], *q1 = uv + 2 * face[1], *q2 = uv + 2 * face[2];
            double t = b / frame[2];
            double s = (a - frame[1] * t) / frame[0];
            double dx = (q1[0] - q0[0]) * s + (q2[0] - q0[0]) * t, dy = (q1[1] - q0[1]) * s + (q2[1] - q0[1]) * t;
            double dlen = sqrt(dx * dx + dy * dy);
            if (!(dlen > 0))
                continue;
            sum_u += area * projected * dx / dlen;
            sum_v += area * projected * dy / dlen;
        }
        block_sums[block][0] = sum_u;
        block_sums[block][1] = sum_v;
        block_sums[block][2] = area_sum;
    }
    double sum_u = 0, sum_v = 0, area_sum = 0;
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        sum_u += block_sums[block][0];
        sum_v += block_sums[block][1];
        area_sum += block_sums[block][2];
    }
    *norm = sqrt(sum_u * sum_u + sum_v * sum_v);
    if (!(*norm > 1e-3 * area_sum)) {
        *norm = 0;
        return 0;
    }
    return 1.57079632679489661923 - atan2(sum_v, sum_u);
}

/* pz_param_rotate_vertices (lscm.c) for one panel, split across threads when
 * the pattern is one big panel. */
static void rotate_panel(const textile_state *state, int32_t panel, double angle, double *uv)
{
    const panel_system *system = &state->panels[panel];
    int32_t n = system->vertex_count;
    if (angle == 0 || n == 0)
        return;
    double block_sums[SUM_BLOCKS][2], cu = 0, cv = 0;
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        double sum_u = 0, sum_v = 0;
        for (int32_t l = block_start(0, n, block); l < block_start(0, n, block + 1); ++l) {
            sum_u += uv[2 * system->vertices[l]];
            sum_v += uv[2 * system->vertices[l] + 1];
        }
        block_sums[block][0] = sum_u;
        block_sums[block][1] = sum_v;
    }
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        cu += block_sums[block][0];
        cv += block_sums[block][1];
    }
    cu /= n;
    cv /= n;
    double c = cos(angle), s = sin(angle);
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
    for (int32_t l = 0; l < n; ++l) {
        double *p = uv + 2 * system->vertices[l];
        double x = p[0] - cu, y = p[1] - cv;
        p[0] = cu + c * x - s * y;
        p[1] = cv + s * x + c * y;
    }
}

/* Step 1: rigid rotation of every panel so its warp follows the grain. */
void textile_align_grain(textile_state *state, double *uv)
{
    const pz_pattern *pattern = state->pattern;
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->across_panels)
    for (int32_t p = 0; p < pattern->panel_count; ++p)
        rotate_panel(state, p, panel_grain_angle(state, p, uv, &state->grain_norm[p]), uv);
}

/*
 * The gradient of panel p's grain angle (panel_grain_angle: theta = pi/2 -
 * atan2(S_v, S_u), S the weighted sum of the faces' unit 2D grain directions
 * d / |d|) with respect to coordinate k of its vertices, at an aligned uv (S
 * along +v, so d theta = dS_u / |S|): per face w (e_u - dhat_u dhat)_k / |d|
 * times d's coefficient of each corner. gradient: the panel's vertex_count,
 * written.
 */
void textile_grain_gradient(const textile_state *state, int32_t panel, int k, const double *uv, double *gradient)
{
    const pz_mesh *mesh = state->pattern->mesh;
    memset(gradient, 0, (size_t)state->panels[panel].vertex_count * sizeof(double));
    double glen = sqrt(dot3(state->grain, state->grain)), norm = state->grain_norm[panel];
    if (!(norm > 0))
        return;
    for (int32_t i = state->offsets[panel]; i < state->offsets[panel + 1]; ++i) {
        int32_t f = state->order[i];
        const int32_t *face = mesh->faces + 3 * f;
        const double *frame = state->frames + (size_t)f * state->pose_total * 3;
        double a = state->grain_local[2 * f] / glen, b = state->grain_local[2 * f + 1] / glen;
        double projected = sqrt(a * a + b * b);
        if (state->areas[f] <= 0 || projected < 1e-9)
            continue;
        /* As in panel_grain_angle: d = (q1 - q0) s + (q2 - q0) t. */
        double t = b / frame[2], s = (a - frame[1] * t) / frame[0];
        const double *q0 = uv + 2 * face[0], *q1 = uv + 2 * face[1], *q2 = uv + 2 * face[2];
        double dx = (q1[0] - q0[0]) * s + (q2[0] - q0[0]) * t, dy = (q1[1] - q0[1]) * s + (q2[1] - q0[1]) * t;
        double dlen = sqrt(dx * dx + dy * dy);
        if (!(dlen > 0))
            continue;
        double ux = dx / dlen, uy = dy / dlen;
        double g = state->areas[f] * projected * ((k == 0 ? 1 : 0) - ux * (k == 0 ? ux : uy)) / (dlen * norm);
        gradient[state->vertex_local[face[1]]] += g * s;
        gradient[state->vertex_local[face[2]]] += g * t;
        gradient[state->vertex_local[face[0]]] -= g * (s + t);
    }
}

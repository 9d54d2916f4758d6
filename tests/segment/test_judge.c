/*
 * tests/segment/test_judge.c -- the one goal judge (pz_goal_judge): every
 * goal judged from a panel's figures alone, figures not measured left
 * unjudged, the caller's veto kept, the defaults defined once
 * (pz_goal_options_default), and the description naming each failure.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"

#include "test_util.h"

#include <math.h>
#include <string.h>

/* A disk panel with 4 corners, flattened with strain 0.01, no flips, seams 0.1 % apart. */
static pz_goal_result sound_panel(void)
{
    pz_goal_result figures = {0};
    figures.disk = 1;
    figures.corners = 4;
    figures.boundary_loops = 1;
    figures.max_abs_strain = 0.01;
    figures.max_seam_mismatch = 0.001;
    figures.min_dart_opening_deg = -1;
    return figures;
}

static void test_defaults(void)
{
    pz_goal_options goals;
    memset(&goals, 0x5a, sizeof goals);
    pz_goal_options_default(&goals);
    CHECK(goals.max_corners == 8 && goals.max_strain == 0.05 && goals.max_seam_mismatch == 0.005,
          "defaults C %d S %g seam %g", (int)goals.max_corners, goals.max_strain, goals.max_seam_mismatch);
    CHECK(goals.grain[0] == 0 && goals.grain[1] == 0 && goals.grain[2] == 1 && goals.textile_iterations == 0,
          "default grain or iterations");
    pz_segment_options segment;
    pz_segment_options_default(&segment);
    CHECK(segment.max_corners == goals.max_corners && segment.max_strain == goals.max_strain,
          "the segmentation's defaults (C %d, S %g) differ from the goals'", (int)segment.max_corners,
          segment.max_strain);
}

static void test_each_goal(void)
{
    pz_goal_options goals;
    pz_goal_options_default(&goals);
    pz_goal_result figures = sound_panel();
    CHECK(pz_goal_judge(&goals, &figures) == 0, "a sound panel fails: %u", pz_goal_judge(&goals, &figures));

    figures = sound_panel(), figures.disk = 0;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_NOT_DISK, "not a disk: %u", pz_goal_judge(&goals, &figures));
    figures = sound_panel(), figures.corners = 9;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_CORNERS, "9 corners: %u", pz_goal_judge(&goals, &figures));
    figures.corners = 8;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "8 corners are allowed");
    figures = sound_panel(), figures.max_abs_strain = 0.0501;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_STRAIN, "strain 0.0501: %u", pz_goal_judge(&goals, &figures));
    figures.max_abs_strain = NAN;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_STRAIN, "a NaN strain passes");
    figures = sound_panel(), figures.flipped_triangles = 1;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_NOT_INJECTIVE, "a flip passes");
    figures = sound_panel(), figures.boundary_self_intersections = 2;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_NOT_INJECTIVE, "a crossing outline passes");
    figures = sound_panel(), figures.max_seam_mismatch = 0.006;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_SEAM_MISMATCH, "seams 0.6 %% apart: %u",
          pz_goal_judge(&goals, &figures));
    goals.max_seam_mismatch = 0.01;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "seams 0.6 %% apart fail a 1 %% goal");
    pz_goal_options_default(&goals);
    goals.max_corners = 0;  /* 0 = the default C */
    figures = sound_panel(), figures.corners = 9;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_CORNERS, "C = 0 is not the default 8");
}

static void test_unmeasured_and_veto(void)
{
    pz_goal_options goals;
    pz_goal_options_default(&goals);
    /* A panel not flattened (strain -1, as the segmentation leaves a panel it must split anyway) and an
     * evaluation that has no partner panels (seam mismatch -1) are not judged on those goals. */
    pz_goal_result figures = sound_panel();
    figures.max_abs_strain = -1;
    figures.flipped_triangles = 3;
    figures.max_seam_mismatch = -1;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "unmeasured figures judged: %u", pz_goal_judge(&goals, &figures));
    /* The veto is the caller's verdict: kept; every other bit is judged again. */
    figures = sound_panel();
    figures.failures = PZ_GOAL_VETOED | PZ_GOAL_STRAIN | PZ_GOAL_CORNERS;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_VETOED, "stale bits kept or veto lost: %u",
          pz_goal_judge(&goals, &figures));
}

static void test_describe(void)
{
    pz_goal_options goals;
    pz_goal_options_default(&goals);
    pz_goal_result figures = sound_panel();
    figures.corners = 11;
    figures.max_abs_strain = 0.071;
    figures.max_seam_mismatch = 0.008;
    figures.failures = pz_goal_judge(&goals, &figures);
    char text[256];
    pz_goal_describe(&figures, &goals, text, sizeof text);
    CHECK(strcmp(text, "11 corners > 8, strain 0.071 > 0.05, seam mismatch 0.8% > 0.5%") == 0, "describe: '%s'",
          text);
}

int main(void)
{
    test_defaults();
    test_each_goal();
    test_unmeasured_and_veto();
    test_describe();
    return test_finish();
}

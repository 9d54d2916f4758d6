/*
 * tests/segment/test_judge.c -- the one goal judge (pz_goal_judge): every
 * goal judged from a panel's figures alone, figures not measured left
 * unjudged, the caller's veto kept, the defaults defined once
 * (pz_goal_options_default), and the description naming each failure;
 * the piece shapes (width, area, across the grain) and the darts' intake,
 * with what the input forces left unjudged.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"

#include "test_util.h"

#include <math.h>
#include <string.h>

/* A disk panel with 4 corners, flattened with strain 0.01, no flips, seams 0.1 % apart, 150 mm wide, 20 % of
 * the area, 600 mm across the grain, no dart. */
static pz_goal_result sound_panel(void)
{
    pz_goal_result figures = {0};
    figures.disk = 1;
    figures.corners = 4;
    figures.boundary_loops = 1;
    figures.max_abs_strain = 0.01;
    figures.max_seam_mismatch = 0.001;
    figures.min_dart_opening_deg = -1;
    figures.min_width_mm = 150;
    figures.area_share = 0.2;
    figures.across_grain_mm = 600;
    figures.min_dart_intake_mm = -1;
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
    CHECK(goals.min_piece_width_mm == 40 && goals.min_piece_area == 0.01 && goals.max_piece_width_mm == 0 &&
              goals.min_dart_intake_mm == 6,
          "default piece shapes: width %g, area %g, across the grain %g, dart intake %g", goals.min_piece_width_mm,
          goals.min_piece_area, goals.max_piece_width_mm, goals.min_dart_intake_mm);
    pz_segment_options segment;
    pz_segment_options_default(&segment);
    CHECK(segment.max_corners == goals.max_corners && segment.max_strain == goals.max_strain,
          "the segmentation's defaults (C %d, S %g) differ from the goals'", (int)segment.max_corners,
          segment.max_strain);
    CHECK(segment.min_piece_width_mm == goals.min_piece_width_mm && segment.min_piece_area == goals.min_piece_area &&
              segment.max_piece_width_mm == goals.max_piece_width_mm &&
              segment.min_dart_intake_mm == goals.min_dart_intake_mm,
          "the segmentation's piece-shape defaults differ from the goals'");
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

/* The piece shapes and the darts' intake (docs/segment.md, "Piece shapes"). */
static void test_shape_goals(void)
{
    pz_goal_options goals;
    pz_goal_options_default(&goals);
    pz_goal_result figures = sound_panel();
    figures.min_width_mm = 39.9;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_NARROW, "39.9 mm wide: %u", pz_goal_judge(&goals, &figures));
    figures.min_width_mm = 0;  /* a strip whose every vertex lies on its outline: measured, and narrow */
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_NARROW, "0 mm wide: %u", pz_goal_judge(&goals, &figures));
    figures.min_width_mm = 40;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "40 mm wide fails");
    figures.min_width_mm = 20, figures.width_forced = 1;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "narrow by the input's own boundary fails");
    figures = sound_panel(), figures.area_share = 0.0099;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_SMALL, "0.99 %% of the area: %u", pz_goal_judge(&goals, &figures));
    figures.area_forced = 1;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "a whole component fails on its area");
    figures = sound_panel(), figures.across_grain_mm = 1500;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "judged across the grain without a fabric width");
    goals.max_piece_width_mm = 1480;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_FABRIC_WIDTH, "1500 mm on 1480 mm of fabric: %u",
          pz_goal_judge(&goals, &figures));
    figures.across_grain_mm = 1480;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "1480 mm on 1480 mm of fabric fails");
    pz_goal_options_default(&goals);
    figures = sound_panel(), figures.darts = 2, figures.min_dart_intake_mm = 5.9;
    CHECK(pz_goal_judge(&goals, &figures) == PZ_GOAL_DART_INTAKE, "a dart taking in 5.9 mm: %u",
          pz_goal_judge(&goals, &figures));
    figures.min_dart_intake_mm = 6;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "a dart taking in 6 mm fails");
    /* 0 turns a goal off. */
    goals.min_piece_width_mm = goals.min_piece_area = goals.min_dart_intake_mm = 0;
    figures.min_width_mm = 1, figures.area_share = 1e-4, figures.min_dart_intake_mm = 0.01;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "goals set to 0 judged: %u", pz_goal_judge(&goals, &figures));
    /* The shapes fail a split never mends; the others a split can. */
    CHECK((PZ_GOAL_SPLIT_MENDS & (PZ_GOAL_SHAPE | PZ_GOAL_DART_INTAKE | PZ_GOAL_SEAM_MISMATCH)) == 0 &&
              (PZ_GOAL_SPLIT_MENDS & PZ_GOAL_STRAIN) && (PZ_GOAL_SPLIT_MENDS & PZ_GOAL_FABRIC_WIDTH),
          "the split mask");
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
    figures.min_width_mm = figures.area_share = figures.across_grain_mm = -1;
    figures.darts = 1, figures.min_dart_intake_mm = -1;
    goals.max_piece_width_mm = 1000;
    CHECK(pz_goal_judge(&goals, &figures) == 0, "unmeasured figures judged: %u", pz_goal_judge(&goals, &figures));
    pz_goal_options_default(&goals);
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
    figures = sound_panel();
    figures.min_width_mm = 31.25, figures.area_share = 0.004, figures.across_grain_mm = 1612;
    figures.darts = 1, figures.min_dart_intake_mm = 2.5;
    goals.max_piece_width_mm = 1480;
    figures.failures = pz_goal_judge(&goals, &figures);
    pz_goal_describe(&figures, &goals, text, sizeof text);
    CHECK(strcmp(text, "31.2 mm wide < 40 mm, 0.4% of the area < 1%, 1612 mm across the grain > 1480 mm of fabric, "
                       "dart intake 2.5 mm < 6 mm") == 0,
          "describe: '%s'", text);
}

int main(void)
{
    test_defaults();
    test_each_goal();
    test_shape_goals();
    test_unmeasured_and_veto();
    test_describe();
    return test_finish();
}

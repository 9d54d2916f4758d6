/*
 * pipeline/cmd_run.c -- `panelize run GARMENT -o DIR` (being written).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/cli.h"

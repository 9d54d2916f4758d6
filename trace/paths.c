/*
 * trace/paths.c -- (being written)
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "trace/trace.h"

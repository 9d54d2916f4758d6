/*
 * export/export.c -- (being written)
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"

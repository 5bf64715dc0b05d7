/*
 * fuzz_util.h - what the libFuzzer targets share: GDAL set up once, errors
 * kept quiet, and a scene run to the output of its first blocks.
 */
#ifndef WM_FUZZ_UTIL_H
#define WM_FUZZ_UTIL_H

#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>

/* Blocks of a scene a run goes through: "down to one block's output", and
 * a few more so that seams and the walk are exercised. */
#define FUZZ_BLOCKS 4

static int fuzz_free_block(void *user, wm_block_result *res, void *prep)
{
    (void)user;
    (void)prep;
    wm_block_result_free(res);
    return TRUE;
}

/* Runs the first FUZZ_BLOCKS blocks of s on one thread. */
static void fuzz_run_scene(WMScene *s)
{
    WMBlockWalk w;
    int64_t blocks[2 * FUZZ_BLOCKS];
    size_t n = 0;
    WMBlockWalkBegin(&w, s, NULL);
    if (WMBlockWalkNext(&w, blocks, FUZZ_BLOCKS, &n) && n > 0)
    {
        WMRunStats st;
        const WMBlockSink sink = {fuzz_free_block, NULL, NULL, NULL};
        WMRunBlocks(s, blocks, n, &sink, NULL, NULL, &st);
    }
    WMBlockWalkEnd(&w);
}

static void fuzz_setup(void)
{
    GDALAllRegister();
    CPLSetErrorHandler(CPLQuietErrorHandler);
    /* nothing reaches out of the process */
    CPLSetConfigOption("GDAL_HTTP_TIMEOUT", "1");
    CPLSetConfigOption("CPL_VSIL_CURL_ALLOWED_EXTENSIONS", "none");
}

#endif

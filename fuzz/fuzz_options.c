/*
 * fuzz_options.c - libFuzzer target: option parsing. The input is a list
 * of NAME=VALUE lines, as open options, creation options or the CLI's
 * switches arrive; WMParamsParse accepts them or refuses with a CPLError.
 */
#include "fuzz_util.h"

#include <cpl_string.h>
#include <stdint.h>
#include <string.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_setup();
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = CPLMalloc(size + 1);
    memcpy(text, data, size);
    text[size] = '\0';
    char **opts = CSLTokenizeString2(text, "\n", 0);
    CPLFree(text);
    WMParams p;
    memset(&p, 0, sizeof p);
    if (WMParamsParse(opts, &p))
        WMParamsFree(&p);
    CSLDestroy(opts);
    CPLErrorReset();
    return 0;
}

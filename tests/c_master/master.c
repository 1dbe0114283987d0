/*
 * A small FMI 2.0 co-simulation master in C, the way a C importer uses an
 * FMU's shared library: dlopen, every function through dlsym, two
 * instances, initialisation, fixed steps, outputs read after each step, FMU
 * state get/set, serialization into the second instance, free, dlclose.
 * Run by tests/fmi_c_master.rs (also under valgrind when it is installed).
 *
 * usage: master LIBRARY GUID RESOURCE_URI STEP N_SAVE N_AFTER VR[,VR...] [--dump]
 *
 *   Instance a is initialised and stepped N_SAVE steps of STEP seconds; its
 *   state is saved and serialized; it steps N_AFTER more (the reference),
 *   is set back to the saved state and steps N_AFTER again; instance b,
 *   never initialised, gets the deserialized state and steps N_AFTER. The
 *   Real variables VR are read after every step: all finite, and both
 *   replays equal to the reference bit for bit. --dump prints a's outputs
 *   after every step as hexadecimal floats (to compare builds).
 *
 * Exit status 0 when everything held; otherwise 1 with a message on stderr.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_decl.h"

struct lib {
    void *handle;
    fmi2_get_string_fn get_version;
    fmi2_get_string_fn get_types_platform;
    fmi2_instantiate_fn instantiate;
    fmi2_free_instance_fn free_instance;
    fmi2_setup_experiment_fn setup_experiment;
    fmi2_component_fn enter_initialization_mode;
    fmi2_component_fn exit_initialization_mode;
    fmi2_component_fn terminate;
    fmi2_get_real_fn get_real;
    fmi2_do_step_fn do_step;
    fmi2_get_state_fn get_state;
    fmi2_set_state_fn set_state;
    fmi2_free_state_fn free_state;
    fmi2_state_size_fn state_size;
    fmi2_serialize_fn serialize;
    fmi2_deserialize_fn deserialize;
};

static int logged_errors;

static void fail(const char *what)
{
    fprintf(stderr, "c master: FAILED: %s\n", what);
    exit(1);
}

static void check(int status, const char *what)
{
    if (status != FMI2_OK) {
        fprintf(stderr, "c master: FAILED: %s returned status %d\n", what, status);
        exit(1);
    }
}

/* The logger: formats the message; warnings and errors go to stderr. */
static void logger(fmi2_environment env, fmi2_string instance_name, int status,
                   fmi2_string category, fmi2_string format, ...)
{
    char text[2048];
    va_list args;
    (void)env;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    if (status >= FMI2_WARNING) {
        fprintf(stderr, "c master: [%s] status %d, %s: %s\n", instance_name ? instance_name : "?",
                status, category ? category : "?", text);
    }
    if (status >= FMI2_ERROR) {
        logged_errors++;
    }
}

static void *allocate(size_t count, size_t size)
{
    return calloc(count, size);
}

static void *symbol(void *handle, const char *name)
{
    void *p = dlsym(handle, name);
    if (p == NULL) {
        fprintf(stderr, "c master: FAILED: symbol %s not found: %s\n", name, dlerror());
        exit(1);
    }
    return p;
}

/* Object pointer to function pointer: allowed by POSIX for dlsym results. */
#define LOAD(field, name) *(void **)(&lib->field) = symbol(lib->handle, name)

static void load(struct lib *lib, const char *path)
{
    lib->handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib->handle == NULL) {
        fprintf(stderr, "c master: FAILED: dlopen %s: %s\n", path, dlerror());
        exit(1);
    }
    LOAD(get_version, "fmi2GetVersion");
    LOAD(get_types_platform, "fmi2GetTypesPlatform");
    LOAD(instantiate, "fmi2Instantiate");
    LOAD(free_instance, "fmi2FreeInstance");
    LOAD(setup_experiment, "fmi2SetupExperiment");
    LOAD(enter_initialization_mode, "fmi2EnterInitializationMode");
    LOAD(exit_initialization_mode, "fmi2ExitInitializationMode");
    LOAD(terminate, "fmi2Terminate");
    LOAD(get_real, "fmi2GetReal");
    LOAD(do_step, "fmi2DoStep");
    LOAD(get_state, "fmi2GetFMUstate");
    LOAD(set_state, "fmi2SetFMUstate");
    LOAD(free_state, "fmi2FreeFMUstate");
    LOAD(state_size, "fmi2SerializedFMUstateSize");
    LOAD(serialize, "fmi2SerializeFMUstate");
    LOAD(deserialize, "fmi2DeSerializeFMUstate");
}

/* Parses "1,2,10" into a new array; returns the count. */
static size_t parse_vrs(const char *text, fmi2_vr **out)
{
    size_t n = 1, k = 0;
    const char *p;
    char *end;
    for (p = text; *p; p++) {
        if (*p == ',') {
            n++;
        }
    }
    *out = malloc(n * sizeof **out);
    if (*out == NULL) {
        fail("out of memory");
    }
    p = text;
    while (k < n) {
        unsigned long v = strtoul(p, &end, 10);
        if (end == p || (*end != ',' && *end != '\0')) {
            fail("value references: expected a comma-separated list of integers");
        }
        (*out)[k++] = (fmi2_vr)v;
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

/* Steps `c` n times from *t, storing the outputs after each step in rows
 * of `values` (n rows of nvr) and checking they are finite. */
static void run_steps(const struct lib *lib, fmi2_component c, const char *name, double *t,
                      double h, long n, const fmi2_vr *vrs, size_t nvr, double *values,
                      int dump)
{
    char what[128];
    long i;
    size_t j;
    for (i = 0; i < n; i++) {
        snprintf(what, sizeof what, "%s: fmi2DoStep at t = %g s", name, *t);
        check(lib->do_step(c, *t, h, FMI2_TRUE), what);
        *t += h;
        snprintf(what, sizeof what, "%s: fmi2GetReal after step %ld", name, i + 1);
        check(lib->get_real(c, vrs, nvr, values + (size_t)i * nvr), what);
        for (j = 0; j < nvr; j++) {
            double x = values[(size_t)i * nvr + j];
            if (!isfinite(x)) {
                fprintf(stderr, "c master: FAILED: %s: vr %u = %g after step %ld\n", name,
                        vrs[j], x, i + 1);
                exit(1);
            }
        }
        if (dump) {
            printf("%s %.6f", name, *t);
            for (j = 0; j < nvr; j++) {
                printf(" %a", values[(size_t)i * nvr + j]);
            }
            printf("\n");
        }
    }
}

/* Bit-for-bit comparison of two runs' outputs. */
static void same_bits(const double *reference, const double *replay, size_t count,
                      const char *what)
{
    size_t k;
    for (k = 0; k < count; k++) {
        if (memcmp(&reference[k], &replay[k], sizeof(double)) != 0) {
            fprintf(stderr, "c master: FAILED: %s differs at value %zu: %.17g against %.17g\n",
                    what, k, replay[k], reference[k]);
            exit(1);
        }
    }
}

int main(int argc, char **argv)
{
    struct lib lib_storage;
    struct lib *lib = &lib_storage;
    struct fmi2_callbacks callbacks;
    fmi2_component a, b;
    fmi2_state saved = NULL, restored = NULL;
    fmi2_vr *vrs = NULL;
    size_t nvr, size = 0;
    fmi2_byte *bytes;
    double h, t, t_saved, *reference, *replay;
    long n_save, n_after;
    int dump;

    if (argc != 8 && argc != 9) {
        fprintf(stderr,
                "usage: %s LIBRARY GUID RESOURCE_URI STEP N_SAVE N_AFTER VR[,VR...] [--dump]\n",
                argv[0]);
        return 2;
    }
    h = strtod(argv[4], NULL);
    n_save = strtol(argv[5], NULL, 10);
    n_after = strtol(argv[6], NULL, 10);
    if (!(h > 0.0) || n_save < 0 || n_after < 1) {
        fail("STEP must be > 0, N_SAVE >= 0 and N_AFTER >= 1");
    }
    nvr = parse_vrs(argv[7], &vrs);
    dump = argc == 9 && strcmp(argv[8], "--dump") == 0;
    if (argc == 9 && !dump) {
        fail("the last argument may only be --dump");
    }

    memset(&lib_storage, 0, sizeof lib_storage);
    load(lib, argv[1]);
    if (strcmp(lib->get_version(), "2.0") != 0) {
        fail("fmi2GetVersion is not \"2.0\"");
    }
    if (strcmp(lib->get_types_platform(), "default") != 0) {
        fail("fmi2GetTypesPlatform is not \"default\"");
    }

    callbacks.logger = logger;
    callbacks.allocate_memory = allocate;
    callbacks.free_memory = free;
    callbacks.step_finished = NULL;
    callbacks.environment = NULL;
    a = lib->instantiate("a", FMI2_CO_SIMULATION, argv[2], argv[3], &callbacks, FMI2_FALSE,
                         FMI2_FALSE);
    b = lib->instantiate("b", FMI2_CO_SIMULATION, argv[2], argv[3], &callbacks, FMI2_FALSE,
                         FMI2_FALSE);
    if (a == NULL || b == NULL) {
        fail("fmi2Instantiate returned NULL");
    }

    check(lib->setup_experiment(a, FMI2_FALSE, 0.0, 0.0, FMI2_FALSE, 0.0), "a: fmi2SetupExperiment");
    check(lib->enter_initialization_mode(a), "a: fmi2EnterInitializationMode");
    check(lib->exit_initialization_mode(a), "a: fmi2ExitInitializationMode");

    reference = malloc((size_t)(n_save > n_after ? n_save : n_after) * nvr * sizeof(double));
    replay = malloc((size_t)n_after * nvr * sizeof(double));
    if (reference == NULL || replay == NULL) {
        fail("out of memory");
    }
    t = 0.0;
    run_steps(lib, a, "a", &t, h, n_save, vrs, nvr, reference, dump);

    /* save and serialize */
    check(lib->get_state(a, &saved), "a: fmi2GetFMUstate");
    check(lib->state_size(a, saved, &size), "a: fmi2SerializedFMUstateSize");
    if (size == 0) {
        fail("the serialized FMU state is empty");
    }
    bytes = malloc(size);
    if (bytes == NULL) {
        fail("out of memory");
    }
    check(lib->serialize(a, saved, bytes, size), "a: fmi2SerializeFMUstate");
    t_saved = t;

    /* the reference, then a replay in the same instance */
    run_steps(lib, a, "a", &t, h, n_after, vrs, nvr, reference, dump);
    check(lib->set_state(a, saved), "a: fmi2SetFMUstate");
    t = t_saved;
    run_steps(lib, a, "a-replay", &t, h, n_after, vrs, nvr, replay, 0);
    same_bits(reference, replay, (size_t)n_after * nvr, "a after fmi2SetFMUstate");
    check(lib->free_state(a, &saved), "a: fmi2FreeFMUstate");
    if (saved != NULL) {
        fail("fmi2FreeFMUstate did not set the state pointer to NULL");
    }

    /* the serialized state into the other instance */
    check(lib->deserialize(b, bytes, size, &restored), "b: fmi2DeSerializeFMUstate");
    check(lib->set_state(b, restored), "b: fmi2SetFMUstate");
    check(lib->free_state(b, &restored), "b: fmi2FreeFMUstate");
    t = t_saved;
    memset(replay, 0, (size_t)n_after * nvr * sizeof(double));
    run_steps(lib, b, "b", &t, h, n_after, vrs, nvr, replay, 0);
    same_bits(reference, replay, (size_t)n_after * nvr, "b from the serialized state");

    check(lib->terminate(a), "a: fmi2Terminate");
    check(lib->terminate(b), "b: fmi2Terminate");
    lib->free_instance(a);
    lib->free_instance(b);
    free(bytes);
    free(reference);
    free(replay);
    free(vrs);
    if (dlclose(lib->handle) != 0) {
        fprintf(stderr, "c master: FAILED: dlclose: %s\n", dlerror());
        return 1;
    }
    if (logged_errors != 0) {
        fail("the FMU logged errors");
    }
    printf("c master: ok: %s, %zu outputs, %ld + %ld steps of %g s, state of %zu bytes "
           "restored bit for bit in both instances\n",
           argv[1], nvr, n_save, n_after, h, size);
    return 0;
}

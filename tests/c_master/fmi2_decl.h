/*
 * The subset of the FMI 2.0 C interface the test master calls, declared for
 * this project from the FMI 2.0 specification's function signatures (section
 * 2.1 and 4.2 of the specification; the standard's own header files are not
 * used). Types follow the "default" platform: fmi2Real is double,
 * fmi2Boolean and fmi2Integer are int, fmi2Byte is char.
 */
#ifndef GEARPUMP_TEST_FMI2_DECL_H
#define GEARPUMP_TEST_FMI2_DECL_H

#include <stddef.h>

typedef void *fmi2_component;
typedef void *fmi2_environment;
typedef void *fmi2_state;
typedef unsigned int fmi2_vr;
typedef double fmi2_real;
typedef int fmi2_bool;
typedef char fmi2_byte;
typedef const char *fmi2_string;

enum { FMI2_FALSE = 0, FMI2_TRUE = 1 };

/* fmi2Status */
enum {
    FMI2_OK = 0,
    FMI2_WARNING = 1,
    FMI2_DISCARD = 2,
    FMI2_ERROR = 3,
    FMI2_FATAL = 4,
    FMI2_PENDING = 5
};

/* fmi2Type */
enum { FMI2_MODEL_EXCHANGE = 0, FMI2_CO_SIMULATION = 1 };

/* fmi2CallbackFunctions, member for member. */
typedef void (*fmi2_logger_fn)(fmi2_environment env, fmi2_string instance_name, int status,
                               fmi2_string category, fmi2_string format, ...);
typedef void *(*fmi2_allocate_fn)(size_t count, size_t size);
typedef void (*fmi2_free_fn)(void *p);
typedef void (*fmi2_step_finished_fn)(fmi2_environment env, int status);

struct fmi2_callbacks {
    fmi2_logger_fn logger;
    fmi2_allocate_fn allocate_memory;
    fmi2_free_fn free_memory;
    fmi2_step_finished_fn step_finished;
    fmi2_environment environment;
};

/* The functions, as pointer types for dlsym. */
typedef const char *(*fmi2_get_string_fn)(void);
typedef fmi2_component (*fmi2_instantiate_fn)(fmi2_string instance_name, int fmu_type,
                                              fmi2_string guid, fmi2_string resource_location,
                                              const struct fmi2_callbacks *functions,
                                              fmi2_bool visible, fmi2_bool logging_on);
typedef void (*fmi2_free_instance_fn)(fmi2_component c);
typedef int (*fmi2_setup_experiment_fn)(fmi2_component c, fmi2_bool tolerance_defined,
                                        fmi2_real tolerance, fmi2_real start_time,
                                        fmi2_bool stop_time_defined, fmi2_real stop_time);
typedef int (*fmi2_component_fn)(fmi2_component c);
typedef int (*fmi2_get_real_fn)(fmi2_component c, const fmi2_vr *vr, size_t n, fmi2_real *value);
typedef int (*fmi2_do_step_fn)(fmi2_component c, fmi2_real current_point, fmi2_real step,
                               fmi2_bool no_set_state_prior);
typedef int (*fmi2_get_state_fn)(fmi2_component c, fmi2_state *state);
typedef int (*fmi2_set_state_fn)(fmi2_component c, fmi2_state state);
typedef int (*fmi2_free_state_fn)(fmi2_component c, fmi2_state *state);
typedef int (*fmi2_state_size_fn)(fmi2_component c, fmi2_state state, size_t *size);
typedef int (*fmi2_serialize_fn)(fmi2_component c, fmi2_state state, fmi2_byte *bytes,
                                 size_t size);
typedef int (*fmi2_deserialize_fn)(fmi2_component c, const fmi2_byte *bytes, size_t size,
                                   fmi2_state *state);

#endif

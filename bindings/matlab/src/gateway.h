/*
 * Shared by the files of the hystcomp MEX gateway (the C files of src/, built into one MEX file,
 * hystcomp_mex): errors, checked arguments, model structs and the compensator handle table.
 * The gateway converts and checks; the C library (bindings/c/include/hystcomp.h) computes.
 */
#ifndef HYSTCOMP_GATEWAY_H
#define HYSTCOMP_GATEWAY_H

#include <stddef.h>
#include <stdint.h>

#include "mex.h"

#include "hystcomp.h"

/* ---- errors and checked arguments (args.c) ------------------------------------------------ */

/* Raises a MATLAB error with identifier `id` and a printf-style message; never returns.
 * Everything the caller owns (library handles) must be released before. */
void fail(const char *id, const char *format, ...);
/* Raises the library's error of a failed call: its message, its status's identifier. */
void fail_status(int status);
/* The MATLAB identifier of a library status (hystcomp:notInvertible, ...). */
const char *status_id(int status);
/* A real, full double array, or an error naming `what` (hystcomp:wrongType). */
void require_double(const mxArray *a, const char *what);
/* A real double scalar (hystcomp:wrongType, hystcomp:wrongSize). */
double scalar(const mxArray *a, const char *what);
/* A finite real double scalar (also hystcomp:nonFiniteInput). */
double finite_scalar(const mxArray *a, const char *what);
/* A whole number from 0 to `max`, as a size (hystcomp:invalidArgument). */
size_t count(const mxArray *a, const char *what, double max);
/* true/false or 1/0 (hystcomp:wrongType). */
int flag(const mxArray *a, const char *what);
/* A non-empty real double vector of finite samples; its length in *len (hystcomp:wrongType,
 * hystcomp:wrongSize, hystcomp:empty, hystcomp:nonFiniteInput with the 1-based index). */
const double *signal(const mxArray *a, const char *what, size_t *len);
/* A character row vector as UTF-8 (freed by MATLAB when the call ends). */
char *string(const mxArray *a, const char *what);
/* Case-insensitive equality of ASCII names. */
int same_name(const char *a, const char *b);
/* A new double vector of `len` values, a row or a column as `like` is. */
mxArray *like_shape(const mxArray *like, size_t len);

/* ---- model structs (model.c) -------------------------------------------------------------- */

/* The C model of a model struct (or of a model file's name); the caller frees it. */
HystcompModel *model_from(const mxArray *s);
/* The model struct of a C model; frees the C model. */
mxArray *model_struct(HystcompModel *model);

/* ---- the compensator handle table (handles.c) --------------------------------------------- */

/* Stores a compensator and returns its id; on failure frees it and raises an error. */
uint64_t handle_store(HystcompCompensator *c);
/* The live compensator of an id, or hystcomp:invalidHandle. */
HystcompCompensator *handle_get(const mxArray *id);
/* Frees the compensator of an id; 0 (and nothing done) when the id is not alive. */
int handle_free(const mxArray *id);
/* How many compensators are alive. */
unsigned handle_count(void);

#endif

/* A stand-in for Fluent's udf.h: declares only what mfflap's generated UDFs use, so that they
   can be compiled (gcc -fsyntax-only, or into a test program) where Fluent is absent.
   Compile with -DND_ND=2 or -DND_ND=3. */
#ifndef MFFLAP_STANDIN_UDF_H
#define MFFLAP_STANDIN_UDF_H
#include <math.h>
#include <stdio.h>
#ifndef ND_ND
#define ND_ND 2
#endif
typedef double real;
typedef struct Dynamic_Thread_struct { int id; } Dynamic_Thread;
#define CURRENT_TIME 0.0
#define Message printf
#define DEFINE_CG_MOTION(name, dt, vel, omega, time, dtime) \
    void name(Dynamic_Thread *dt, real vel[], real omega[], real time, real dtime)
#endif

// Measuring only (2026-12-07-expcost.md): libm's atan2, sincos, sin and cos through their long double
// versions (x87: no FMA variant), so that GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA changes only the other libm
// functions. Build: gcc -O2 -shared -fPIC 2026-12-07-expcost-libm-shim.c -o shim.so -lm
// Use: MCMT_CORNER_DUMP=a.txt LD_PRELOAD=./shim.so bench_detector 60 2 640, then the same with
// GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA into b.txt, and cmp a.txt b.txt.
#define _GNU_SOURCE
#include <math.h>
double atan2(double y, double x) { return (double)atan2l(y, x); }
void sincos(double x, double* s, double* c) {
  long double ls, lc;
  sincosl(x, &ls, &lc);
  *s = (double)ls, *c = (double)lc;
}
double sin(double x) { return (double)sinl(x); }
double cos(double x) { return (double)cosl(x); }

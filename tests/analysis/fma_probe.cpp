// Compiled with -mfma -ffp-contract=fast (tests/analysis/CMakeLists.txt): GCC turns a * b + c into
// one vfmadd, which check_no_fma.py must report (test analysis.no_fma_detects_one).
double fma_probe(double a, double b, double c) { return a * b + c; }

/* libcufft.so.11 for cufinufft's CUDA 12 wheel on a machine with CUDA 13's cuFFT (libcufft.so.12): the five
   functions cufinufft calls, forwarded by dlsym. Device-check tooling only, not part of stipple. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
typedef int cufftResult;
typedef int cufftHandle;
typedef int cufftType;
typedef void *cudaStream_t;
static void *lib;
static void *sym(const char *name) {
    if (!lib) {
        const char *path = getenv("CUFFT_REAL");
        lib = dlopen(path ? path : "libcufft.so.12", RTLD_NOW | RTLD_GLOBAL);
        if (!lib) { fprintf(stderr, "cufft shim: %s\n", dlerror()); abort(); }
    }
    void *s = dlsym(lib, name);
    if (!s) { fprintf(stderr, "cufft shim: no %s\n", name); abort(); }
    return s;
}
cufftResult cufftPlanMany(cufftHandle *plan, int rank, int *n, int *inembed, int istride, int idist, int *onembed,
                          int ostride, int odist, cufftType type, int batch) {
    return ((cufftResult(*)(cufftHandle *, int, int *, int *, int, int, int *, int, int, cufftType, int))sym(
        "cufftPlanMany"))(plan, rank, n, inembed, istride, idist, onembed, ostride, odist, type, batch);
}
cufftResult cufftExecZ2Z(cufftHandle plan, void *in, void *out, int direction) {
    return ((cufftResult(*)(cufftHandle, void *, void *, int))sym("cufftExecZ2Z"))(plan, in, out, direction);
}
cufftResult cufftExecC2C(cufftHandle plan, void *in, void *out, int direction) {
    return ((cufftResult(*)(cufftHandle, void *, void *, int))sym("cufftExecC2C"))(plan, in, out, direction);
}
cufftResult cufftDestroy(cufftHandle plan) { return ((cufftResult(*)(cufftHandle))sym("cufftDestroy"))(plan); }
cufftResult cufftSetStream(cufftHandle plan, cudaStream_t stream) {
    return ((cufftResult(*)(cufftHandle, cudaStream_t))sym("cufftSetStream"))(plan, stream);
}

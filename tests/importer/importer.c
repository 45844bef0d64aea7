/* A minimal FMI 2.0 co-simulation importer for the platform tests (tests/platforms.rs):
 *   importer LIBRARY RESOURCE_URI GUID STOP_TIME STEP [VR=VALUE | VR]...
 * loads the binary (LoadLibrary/GetProcAddress on Windows, dlopen/dlsym elsewhere),
 * instantiates it with logging on, sets each VR=VALUE input, steps from 0 to STOP_TIME and
 * prints `VR VALUE` (%.17g) for each other value reference. Log messages go to stderr. Exit status 1 on any failure. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#ifdef _WIN32
#include <windows.h>
#define LOAD(path) LoadLibraryA(path)
#define SYMBOL(lib, name) ((void *)GetProcAddress(lib, name))
typedef HMODULE Library;
#else
#include <dlfcn.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYMBOL(lib, name) dlsym(lib, name)
typedef void *Library;
#endif

typedef void *Component;
typedef unsigned int ValueReference;
typedef struct {
  void (*logger)(void *, const char *, int, const char *, const char *, ...);
  void *(*allocate)(size_t, size_t);
  void (*free)(void *);
  void (*step_finished)(void *, int);
  void *environment;
} Callbacks;

static void logger(void *env, const char *name, int status, const char *category,
                   const char *message, ...) {
  va_list args;
  (void)env;
  fprintf(stderr, "[%s %d %s] ", name, status, category);
  va_start(args, message);
  vfprintf(stderr, message, args);
  va_end(args);
  fputc('\n', stderr);
}

static Library library;
static void *symbol(const char *name) {
  void *f = SYMBOL(library, name);
  if (!f) {
    fprintf(stderr, "missing export %s\n", name);
    exit(1);
  }
  return f;
}
#define CHECK(call)                                                                    \
  if ((call) != 0) {                                                                   \
    fprintf(stderr, "%s failed\n", #call);                                             \
    return 1;                                                                          \
  }

int main(int argc, char **argv) {
  Callbacks callbacks = {logger, calloc, free, NULL, NULL};
  Component (*instantiate)(const char *, int, const char *, const char *, const Callbacks *,
                           int, int);
  int (*setup)(Component, int, double, double, int, double);
  int (*enter)(Component), (*exit_init)(Component), (*terminate)(Component);
  int (*do_step)(Component, double, double, int);
  int (*get_real)(Component, const ValueReference *, size_t, double *);
  int (*set_real)(Component, const ValueReference *, size_t, const double *);
  void (*free_instance)(Component);
  Component c;
  double stop, step;
  long i, steps;
  if (argc < 7) {
    fprintf(stderr, "usage: importer LIBRARY RESOURCE_URI GUID STOP_TIME STEP [VR=VALUE | VR]...\n");
    return 2;
  }
  library = LOAD(argv[1]);
  if (!library) {
    fprintf(stderr, "cannot load %s\n", argv[1]);
    return 1;
  }
  *(void **)&instantiate = symbol("fmi2Instantiate");
  *(void **)&setup = symbol("fmi2SetupExperiment");
  *(void **)&enter = symbol("fmi2EnterInitializationMode");
  *(void **)&exit_init = symbol("fmi2ExitInitializationMode");
  *(void **)&do_step = symbol("fmi2DoStep");
  *(void **)&get_real = symbol("fmi2GetReal");
  *(void **)&set_real = symbol("fmi2SetReal");
  *(void **)&terminate = symbol("fmi2Terminate");
  *(void **)&free_instance = symbol("fmi2FreeInstance");
  stop = atof(argv[4]);
  step = atof(argv[5]);
  c = instantiate("importer", 1, argv[3], argv[2], &callbacks, 0, 1);
  if (!c) {
    fprintf(stderr, "fmi2Instantiate failed\n");
    return 1;
  }
  CHECK(setup(c, 0, 0.0, 0.0, 1, stop));
  CHECK(enter(c));
  CHECK(exit_init(c));
  for (i = 6; i < argc; i++) {
    char *end;
    ValueReference vr = (ValueReference)strtoul(argv[i], &end, 10);
    double value;
    if (*end != '=') continue;
    value = atof(end + 1);
    CHECK(set_real(c, &vr, 1, &value));
  }
  steps = (long)(stop / step + 0.5);
  for (i = 0; i < steps; i++) CHECK(do_step(c, i * step, step, 1));
  for (i = 6; i < argc; i++) {
    char *end;
    ValueReference vr = (ValueReference)strtoul(argv[i], &end, 10);
    double value;
    if (*end == '=') continue;
    CHECK(get_real(c, &vr, 1, &value));
    printf("%u %.17g\n", vr, value);
  }
  CHECK(terminate(c));
  free_instance(c);
  return 0;
}

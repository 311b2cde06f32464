/*
 * A plugin that misbehaves on purpose, for tests/test_plugin_isolation.cpp. It is built once per behaviour,
 * each with one TWINRAY_HOSTILE_* macro defined (tests/plugins/CMakeLists.txt). Every query answers "miss",
 * except on a trigger ray: one whose direction has an exactly zero component (the classic crash of a slab
 * test that divides by it). Then, by behaviour:
 *
 *   SEGV        prints a line, writes through a null ptr   ALLOC       allocates (and touches) without bound
 *   LOOP        loops forever                              BAD_HIT     reports a hit on geom_id 999
 *   ABORT       calls abort()                              OPEN_READ   opens a file for reading
 *   EXIT        calls exit(3)                              OPEN_WRITE  creates a file for writing
 *   PRINT       prints 120 KiB to stdout and to stderr     SOCKET      opens a TCP socket
 *               while building, then crashes like SEGV     FORK        calls fork()
 *   NORMAL      builds with four threads that allocate     EXEC        calls execl("/bin/true")
 *               and print (what ordinary plugins do)
 *   BUILD_CRASH   writes through a null pointer in build
 *   BUILD_READ    tries to read /etc/passwd in build: the build fails with what happened
 *   BUILD_WRITE   tries to create a file in build
 *   CRASH_AT_100  like SEGV, but its trigger is the 100th query (for the command-line tests, whose rays
 *                 have no zero component)
 *   CREATE_CRASH, CREATE_LOOP, DESTROY_CRASH   crash or loop in create(), crash in destroy()
 *   CLOSE_FDS     closes every descriptor from 0 to 63 in build, as code that "daemonises" does: among them the
 *                 worker's shared memory (3) and lifeline (4), which the sandbox refuses to let go
 *   BUILD_ESCAPES is named, and fails its build with a message, full of terminal escapes, newlines, a fake
 *                 scorecard line and invalid UTF-8
 *   BUILD_LOOP    never returns from build, on any scene (what costs a suite a time limit per check)
 *   SCRIBBLE      maps the worker's shared memory (descriptor 3) in build and starts a thread that fills all of
 *                 it with the byte 0xA5 every two milliseconds: sequence numbers, statuses and counts the
 *                 worker could never write. The build returns once the first fill is done, so the answer to
 *                 the build request is always one of them
 *   EXIT_HANDLER_CRASH  registers an atexit handler in build that writes through a null pointer: everything
 *                 answers, and a program that used it crashes as it ends
 *   EXIT_HANDLER_HANG   registers an atexit handler in build that never returns
 *   LATE_THREAD_CRASH   starts a detached thread in build that sleeps 100 ms and then crashes: a worker that
 *                 dies between two calls, with no call of twinray's waiting for it
 *   SPIN          starts two detached threads in build that spin forever (a busy-waiting thread pool that is
 *                 never stopped): it answers everything, slowly on a busy machine, and ends with its worker
 *   EXIT0_BUILD   calls exit(0) in build (a command-line tool's "done" left in library code): a clean status
 *                 that must still be a crash, not a normal end
 *   THREAD_EXIT0  starts a detached thread in build that calls exit(0) 50 ms later, while queries run
 *   STOP          raises SIGSTOP on itself on a trigger ray (a debugging aid left in): the worker is stopped,
 *                 not dead, and must be cut by the ray's time limit
 *   CHATTY        prints a line on every query (debug output left in), and answers like the others
 *   BATCH_SEGV, BATCH_LOOP  have intersect_batch and occluded_batch, which write through a null pointer / loop
 *                 forever on the third ray of any call of three rays or more; their single-ray functions answer
 *                 every ray (a miss): a bug only the batch path has (tests/test_grade_batch.cpp)
 *   STDOUT_TO_SHM dup2()s the worker's shared memory (descriptor 3) onto stdout in build and prints: the text
 *                 lands in the memory the worker answers through
 *
 * Strict C89 like the other test plugins, plus the POSIX calls it needs.
 */
#define _POSIX_C_SOURCE 200112L

#include "twinray_plugin.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

void crash(void);
void write_message(char* error, size_t capacity, const char* message);
int start_detached(void* (*body)(void*), char* error, size_t capacity);

static void* hostile_create(void) {
#ifdef TWINRAY_HOSTILE_CREATE_CRASH
  crash();
#endif
#ifdef TWINRAY_HOSTILE_CREATE_LOOP
  {
    volatile unsigned long spins = 0;
    for (;;) ++spins;
  }
#endif
  return calloc(1, 16);
}

static void hostile_destroy(void* self) {
#ifdef TWINRAY_HOSTILE_DESTROY_CRASH
  crash();
#endif
  free(self);
}

/* Not static: each build uses only some helpers, and unused static functions would warn. The plugin exports
 * only the entry point either way (hidden visibility). */
void write_message(char* error, size_t capacity, const char* message) {
  size_t k;
  if (capacity == 0) return;
  for (k = 0; k + 1 < capacity && message[k] != '\0'; ++k) error[k] = message[k];
  error[k] = '\0';
}

void crash(void) {
  volatile int* volatile nowhere = NULL;
  *nowhere = 1;
}

/* Starts `body` on a detached thread that outlives the call; 0, or TWINRAY_ERROR with the message set. */
int start_detached(void* (*body)(void*), char* error, size_t capacity) {
  pthread_t thread;
  if (pthread_create(&thread, NULL, body, NULL) != 0) {
    write_message(error, capacity, "pthread_create failed");
    return TWINRAY_ERROR;
  }
  pthread_detach(thread);
  return 0;
}

#ifdef TWINRAY_HOSTILE_NORMAL
static void* normal_worker(void* arg) {
  size_t i, sum = 0;
  size_t* numbers = (size_t*)malloc(1000 * sizeof(size_t));
  if (numbers == NULL) return NULL;
  for (i = 0; i < 1000; ++i) numbers[i] = i;
  for (i = 0; i < 1000; ++i) sum += numbers[i];
  free(numbers);
  *(size_t*)arg = sum;
  return NULL;
}
#endif

#ifdef TWINRAY_HOSTILE_SCRIBBLE
static volatile int scribbled;

static void* scribble(void* arg) {
  const struct stat* st = (const struct stat*)arg;
  void* shared = mmap(NULL, (size_t)st->st_size, PROT_READ | PROT_WRITE, MAP_SHARED, 3, 0);
  struct timespec pause;
  pause.tv_sec = 0;
  pause.tv_nsec = 2000000L;
  if (shared == MAP_FAILED) return NULL;
  for (;;) {
    memset(shared, 0xA5, (size_t)st->st_size);
    scribbled = 1;
    nanosleep(&pause, NULL);
  }
}
#endif

#ifdef TWINRAY_HOSTILE_EXIT_HANDLER_CRASH
static void crash_at_exit(void) { crash(); }
#endif
#ifdef TWINRAY_HOSTILE_EXIT_HANDLER_HANG
static void hang_at_exit(void) {
  struct timespec second;
  second.tv_sec = 1;
  second.tv_nsec = 0;
  for (;;) nanosleep(&second, NULL);
}
#endif
#ifdef TWINRAY_HOSTILE_SPIN
static void* spin_forever(void* arg) {
  volatile unsigned long spins = 0;
  (void)arg;
  for (;;) ++spins;
  return NULL;
}
#endif
#ifdef TWINRAY_HOSTILE_THREAD_EXIT0
static void* exit_later(void* arg) {
  struct timespec pause;
  (void)arg;
  pause.tv_sec = 0;
  pause.tv_nsec = 50000000L;
  nanosleep(&pause, NULL);
  exit(0);
  return NULL;
}
#endif
#ifdef TWINRAY_HOSTILE_LATE_THREAD_CRASH
static void* crash_later(void* arg) {
  struct timespec pause;
  (void)arg;
  pause.tv_sec = 0;
  pause.tv_nsec = 100000000L;
  nanosleep(&pause, NULL);
  crash();
  return NULL;
}
#endif

static int hostile_build(void* self, const twinray_geometry* geometry, char* error, size_t capacity) {
  (void)self;
  (void)geometry;
  (void)error;
  (void)capacity;
#ifdef TWINRAY_HOSTILE_BUILD_CRASH
  crash();
#endif
#ifdef TWINRAY_HOSTILE_EXIT0_BUILD
  exit(0);
#endif
#ifdef TWINRAY_HOSTILE_THREAD_EXIT0
  if (start_detached(exit_later, error, capacity) != 0) return TWINRAY_ERROR;
#endif
#ifdef TWINRAY_HOSTILE_STDOUT_TO_SHM
  if (dup2(3, 1) == 1) {
    int line;
    for (line = 0; line < 64; ++line) printf("line %02d of a plugin whose stdout is the worker's shared memory\n", line);
    fflush(stdout);
  }
#endif
#ifdef TWINRAY_HOSTILE_EXIT_HANDLER_CRASH
  atexit(crash_at_exit);
#endif
#ifdef TWINRAY_HOSTILE_EXIT_HANDLER_HANG
  atexit(hang_at_exit);
#endif
#ifdef TWINRAY_HOSTILE_SPIN
  {
    pthread_t thread;
    int t;
    for (t = 0; t < 2; ++t)
      if (pthread_create(&thread, NULL, spin_forever, NULL) == 0) pthread_detach(thread);
  }
#endif
#ifdef TWINRAY_HOSTILE_LATE_THREAD_CRASH
  if (start_detached(crash_later, error, capacity) != 0) return TWINRAY_ERROR;
#endif
#ifdef TWINRAY_HOSTILE_BUILD_LOOP
  {
    struct timespec second;
    second.tv_sec = 1;
    second.tv_nsec = 0;
    for (;;) nanosleep(&second, NULL); /* a hang that leaves the machine's cores to the other tests */
  }
#endif
#ifdef TWINRAY_HOSTILE_SCRIBBLE
  {
    static struct stat st;
    pthread_t thread;
    struct timespec pause;
    pause.tv_sec = 0;
    pause.tv_nsec = 1000000L;
    if (fstat(3, &st) != 0 || pthread_create(&thread, NULL, scribble, &st) != 0) {
      write_message(error, capacity, "could not start the scribbler");
      return TWINRAY_ERROR;
    }
    while (!scribbled) nanosleep(&pause, NULL);
  }
#endif
#ifdef TWINRAY_HOSTILE_CLOSE_FDS
  {
    int fd;
    for (fd = 0; fd < 64; ++fd) close(fd);
  }
#endif
#ifdef TWINRAY_HOSTILE_BUILD_ESCAPES
  write_message(error, capacity, "\033[2J\033[32mpass\n\rpass        9/9  closest-hit   everything\xff\xfe\x9b");
  return TWINRAY_ERROR;
#endif
#ifdef TWINRAY_HOSTILE_BUILD_READ
  {
    FILE* f = fopen("/etc/passwd", "r");
    if (f != NULL) {
      fclose(f);
      write_message(error, capacity, "opened /etc/passwd");
    } else {
      char message[128];
      sprintf(message, "could not open /etc/passwd: %.80s", strerror(errno));
      write_message(error, capacity, message);
    }
    return TWINRAY_ERROR;
  }
#endif
#ifdef TWINRAY_HOSTILE_BUILD_WRITE
  {
    FILE* f = fopen("/tmp/twinray-hostile-build-write.txt", "w");
    if (f != NULL) fclose(f);
  }
#endif
#ifdef TWINRAY_HOSTILE_PRINT
  {
    int line;
    for (line = 0; line < 2000; ++line) {
      fprintf(stdout, "stdout line %04d of the hostile plugin, padded to fifty bytes\n", line);
      fprintf(stderr, "stderr line %04d of the hostile plugin, padded to fifty bytes\n", line);
    }
    fflush(stdout);
  }
#endif
#ifdef TWINRAY_HOSTILE_NORMAL
  {
    pthread_t threads[4];
    size_t sums[4];
    int t;
    for (t = 0; t < 4; ++t)
      if (pthread_create(&threads[t], NULL, normal_worker, &sums[t]) != 0) {
        write_message(error, capacity, "pthread_create failed");
        return TWINRAY_ERROR;
      }
    for (t = 0; t < 4; ++t) pthread_join(threads[t], NULL);
    printf("built with 4 threads, sums %lu %lu %lu %lu\n", (unsigned long)sums[0], (unsigned long)sums[1],
           (unsigned long)sums[2], (unsigned long)sums[3]);
    fflush(stdout);
  }
#endif
  return TWINRAY_OK;
}

#ifdef TWINRAY_HOSTILE_CRASH_AT_100
static unsigned long queries_so_far; /* one caller at a time in the tests that use it */
static int is_trigger(const twinray_ray* ray) {
  (void)ray;
  return ++queries_so_far == 100;
}
#else
static int is_trigger(const twinray_ray* ray) { return ray->dir[0] == 0.0f || ray->dir[1] == 0.0f || ray->dir[2] == 0.0f; }
#endif

/* What the behaviour does on a trigger ray. Returns 1 when it reports a hit (BAD_HIT). */
static int misbehave(twinray_hit* hit) {
#ifdef TWINRAY_HOSTILE_SEGV
  printf("about to trace a ray with a zero direction component\n"); /* not flushed: the worker must keep it */
#endif
#if defined(TWINRAY_HOSTILE_SEGV) || defined(TWINRAY_HOSTILE_PRINT) || defined(TWINRAY_HOSTILE_CRASH_AT_100)
  crash();
#endif
#ifdef TWINRAY_HOSTILE_LOOP
  {
    volatile unsigned long spins = 0;
    for (;;) ++spins;
  }
#endif
#ifdef TWINRAY_HOSTILE_ABORT
  abort();
#endif
#ifdef TWINRAY_HOSTILE_EXIT
  exit(3);
#endif
#ifdef TWINRAY_HOSTILE_ALLOC
  {
    void* chain = NULL;
    for (;;) {
      char* block = (char*)malloc(1u << 20);
      memset(block, 1, 1u << 20); /* a NULL block faults here once the memory limit is reached */
      *(void**)block = chain;
      chain = block;
    }
  }
#endif
#ifdef TWINRAY_HOSTILE_OPEN_READ
  {
    FILE* f = fopen("/etc/hostname", "r");
    if (f != NULL) fclose(f);
  }
#endif
#ifdef TWINRAY_HOSTILE_OPEN_WRITE
  {
    FILE* f = fopen("/tmp/twinray-hostile-query-write.txt", "w");
    if (f != NULL) fclose(f);
  }
#endif
#ifdef TWINRAY_HOSTILE_SOCKET
  {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd >= 0) close(fd);
  }
#endif
#ifdef TWINRAY_HOSTILE_FORK
  {
    const pid_t child = fork();
    if (child == 0) _exit(0);
  }
#endif
#ifdef TWINRAY_HOSTILE_EXEC
  execl("/bin/true", "true", (char*)NULL);
#endif
#ifdef TWINRAY_HOSTILE_STOP
  raise(SIGSTOP);
#endif
#ifdef TWINRAY_HOSTILE_BAD_HIT
  hit->t = 1.0f;
  hit->u = hit->v = 0.0f;
  hit->geom_id = 999u;
  hit->prim_id = 0u;
  hit->ng[0] = hit->ng[1] = 0.0f;
  hit->ng[2] = 1.0f;
  return 1;
#endif
  (void)hit;
  return 0;
}

static int hostile_intersect1(const void* self, const twinray_ray* ray, twinray_hit* hit, twinray_query_stats* stats) {
  (void)self;
  (void)stats;
#ifdef TWINRAY_HOSTILE_CHATTY
  printf("intersect1: ray from %g %g %g\n", (double)ray->org[0], (double)ray->org[1], (double)ray->org[2]);
#endif
  if (is_trigger(ray)) return misbehave(hit);
  return 0;
}

static int hostile_occluded1(const void* self, const twinray_ray* ray, twinray_query_stats* stats) {
  twinray_hit ignored;
  (void)self;
  (void)stats;
#ifdef TWINRAY_HOSTILE_CHATTY
  fprintf(stderr, "occluded1: ray from %g %g %g\n", (double)ray->org[0], (double)ray->org[1], (double)ray->org[2]);
#endif
  if (is_trigger(ray)) return misbehave(&ignored);
  return 0;
}

#if defined(TWINRAY_HOSTILE_BATCH_SEGV) || defined(TWINRAY_HOSTILE_BATCH_LOOP)
static void batch_misbehave(void) {
#ifdef TWINRAY_HOSTILE_BATCH_SEGV
  crash();
#else
  volatile unsigned long spins = 0;
  for (;;) ++spins;
#endif
}

static void hostile_intersect_batch(const void* self, const twinray_ray* rays, twinray_hit* hits, size_t count,
                                    twinray_query_stats* stats) {
  size_t i;
  (void)self;
  (void)rays;
  (void)stats;
  for (i = 0; i < count; ++i) {
    if (i == 2) batch_misbehave();
    hits[i].geom_id = TWINRAY_INVALID_ID;
  }
}

static void hostile_occluded_batch(const void* self, const twinray_ray* rays, unsigned char* occluded, size_t count,
                                   twinray_query_stats* stats) {
  size_t i;
  (void)self;
  (void)rays;
  (void)stats;
  for (i = 0; i < count; ++i) {
    if (i == 2) batch_misbehave();
    occluded[i] = 0;
  }
}
#define HOSTILE_BATCH_FUNCTIONS hostile_intersect_batch, hostile_occluded_batch
#else
#define HOSTILE_BATCH_FUNCTIONS NULL, NULL
#endif

#ifdef TWINRAY_HOSTILE_BUILD_ESCAPES
#define HOSTILE_NAME "hostile\n\033[1mpass\xff"
#else
#define HOSTILE_NAME "hostile"
#endif
static const twinray_plugin_v1 hostile_table = {
    TWINRAY_PLUGIN_ABI_VERSION, HOSTILE_NAME, 0u, hostile_create, hostile_destroy, hostile_build,
    hostile_intersect1,         hostile_occluded1, HOSTILE_BATCH_FUNCTIONS, NULL,
};

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &hostile_table; }

/* The C ABI attacked from C, as a seeded sweep: options with a cap kind outside the enum,
 * engines of huge dimensions, pushes and rebuilds whose counts pass the end of memory, engines
 * freed and made again (at the same address when the allocator reuses it) and offered to one
 * sampler, updates offered twice, NULL pointers. Every call must return a status; a crash, or
 * a status other than the one the call deserves, fails the sweep. Built with AddressSanitizer
 * and UndefinedBehaviorSanitizer by tests/python/test_capi.py, so that a read or write out of
 * bounds fails too.
 *
 *     attacks SEED ROUNDS
 *
 * prints one line per kind of attack: `kind cases refused accepted`, and exits 1 on the first
 * failure (naming the case) or 0. */

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inexact_loops.h"

static uint64_t state;

/* splitmix64: the sweep's random choices, from the seed. */
static uint64_t next(void) {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static size_t pick(const size_t *values, size_t n) { return values[next() % n]; }

enum Kind { CAP_KIND, DIM, COUNT, REMADE, TWICE, NULLS, KINDS };
static const char *const NAMES[KINDS] = {"cap_kind", "dim", "count", "remade_engine", "offered_twice",
                                         "null_pointers"};
static long cases[KINDS], refused[KINDS], accepted[KINDS];

static void fail(const char *what, unsigned long long value, LoopsStatus status) {
    printf("FAILED %s %llu: status %d: %s\n", what, value, (int)status, loops_last_error());
    exit(1);
}

/* A status for case `value` of `kind`: `expected` is the status it deserves. */
static void check(enum Kind kind, unsigned long long value, LoopsStatus status, LoopsStatus expected) {
    cases[kind]++;
    if (status != expected) fail(NAMES[kind], value, status);
    if (status == LOOPS_STATUS_OK) {
        accepted[kind]++;
    } else {
        refused[kind]++;
        if (strchr(loops_last_error(), '\n') != NULL || loops_last_error()[0] == '\0') {
            fail("message of one line", value, status);
        }
    }
}

static void cap_kinds(void) {
    LoopsSamplerOptions options;
    loops_sampler_options_default(&options);
    const uint32_t kind = (next() % 2) ? (uint32_t)(next() % 8) : (uint32_t)next();
    options.cap_kind = kind;
    options.cap_value = 2.0;
    LoopsSampler *sampler = NULL;
    const LoopsStatus status = loops_sampler_new(&options, &sampler);
    check(CAP_KIND, kind, status, kind <= LOOPS_CAP_KIND_PER_METRE ? LOOPS_STATUS_OK : LOOPS_STATUS_INVALID_PARAMETER);
    loops_sampler_free(sampler);
}

static void dims(void) {
    static const size_t DIMS[] = {1, 3, 7, 65536, 65537, 1000000, (size_t)1 << 40, (size_t)1 << 62, SIZE_MAX};
    const size_t dim = pick(DIMS, sizeof DIMS / sizeof DIMS[0]);
    LoopsOnline *online = NULL;
    const LoopsStatus status = loops_online_new(NULL, dim, 1.0, &online);
    check(DIM, dim, status, dim <= 65536 ? LOOPS_STATUS_OK : LOOPS_STATUS_INVALID_PARAMETER);
    if (online != NULL && dim <= 65536) {
        double *point = calloc(dim, sizeof(double));
        check(DIM, dim, loops_online_push(online, 0.0, point, dim, NULL), LOOPS_STATUS_OK);
        free(point);
    }
    loops_online_free(online);
}

static void counts(void) {
    static const size_t COUNTS[] = {0,          1,           2,           (size_t)1 << 32,
                                    (size_t)1 << 61, SIZE_MAX / 3 + 1, SIZE_MAX};
    const size_t count = pick(COUNTS, sizeof COUNTS / sizeof COUNTS[0]);
    LoopsOnline *online = NULL;
    if (loops_online_new(NULL, 3, 1.0, &online) != LOOPS_STATUS_OK) fail("new", 3, LOOPS_STATUS_OK);
    /* Buffers of two poses: a count beyond them must be refused before anything is read. */
    const double times[2] = {0.0, 1.0}, coords[6] = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0};
    const LoopsStatus fits = count <= 2 ? LOOPS_STATUS_OK : LOOPS_STATUS_INVALID_TRAJECTORY;
    if (next() % 2) {
        check(COUNT, count, loops_online_push_many(online, times, coords, count, 3, NULL), fits);
    } else {
        const LoopsStatus rebuilt = count == 2 ? LOOPS_STATUS_OK : LOOPS_STATUS_INVALID_TRAJECTORY;
        check(COUNT, count, loops_online_rebuild(online, times, coords, count), rebuilt);
    }
    loops_online_free(online);
}

/* Engines freed and made again, each offered to one sampler: every engine is new to it. */
static void remade(LoopsSampler *sampler) {
    LoopsOnline *online = NULL;
    if (loops_online_new(NULL, 2, 1.0, &online) != LOOPS_STATUS_OK) fail("new", 2, LOOPS_STATUS_OK);
    const double times[3] = {0.0, 1.0, 2.0}, coords[6] = {0.0, 0.0, 0.3, 0.0, 0.1, 0.0};
    check(REMADE, 0, loops_online_push_many(online, times, coords, 3, 2, NULL), LOOPS_STATUS_OK);
    LoopsCandidate buffer[8];
    size_t count = 0;
    check(REMADE, 1, loops_sampler_offer(sampler, online, buffer, 8, &count), LOOPS_STATUS_OK);
    int first = 0;
    for (size_t k = 0; k < count && k < 8; k++) first |= buffer[k].first;
    if (!first) fail("a remade engine's first candidate", count, LOOPS_STATUS_OK);
    if (next() % 2) {
        check(TWICE, count, loops_sampler_offer(sampler, online, buffer, 8, &count), LOOPS_STATUS_INVALID_PARAMETER);
    }
    loops_online_free(online);
}

static void nulls(void) {
    size_t count = 0;
    LoopsOnline *online = NULL;
    switch (next() % 4) {
        case 0: check(NULLS, 0, loops_online_new(NULL, 3, 1.0, NULL), LOOPS_STATUS_NULL_POINTER); break;
        case 1: check(NULLS, 1, loops_sampler_new(NULL, NULL), LOOPS_STATUS_NULL_POINTER); break;
        case 2:
            check(NULLS, 2, loops_online_push_many(NULL, NULL, NULL, 0, 3, NULL), LOOPS_STATUS_NULL_POINTER);
            break;
        default:
            loops_online_new(NULL, 3, 1.0, &online);
            check(NULLS, 3, loops_online_components(online, NULL, 4, &count), LOOPS_STATUS_NULL_POINTER);
            loops_online_free(online);
    }
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: attacks SEED ROUNDS\n");
        return 2;
    }
    state = strtoull(argv[1], NULL, 10);
    const long rounds = strtol(argv[2], NULL, 10);
    LoopsSampler *sampler = NULL;
    if (loops_sampler_new(NULL, &sampler) != LOOPS_STATUS_OK) fail("sampler", 0, LOOPS_STATUS_OK);
    for (long round = 0; round < rounds; round++) {
        switch (next() % 5) {
            case 0: cap_kinds(); break;
            case 1: dims(); break;
            case 2: counts(); break;
            case 3: remade(sampler); break;
            default: nulls();
        }
    }
    loops_sampler_free(sampler);
    for (int kind = 0; kind < KINDS; kind++) {
        printf("%s %ld %ld %ld\n", NAMES[kind], cases[kind], refused[kind], accepted[kind]);
    }
    return 0;
}

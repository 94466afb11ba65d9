/* replay.c: the fuzz corpora as a regression test. Runs every file of
 * CORPUS/<target>/ through fuzz_<target>() (the same functions the
 * libFuzzer targets call); a violated check abort()s, failing the test.
 *
 *   fuzz_corpus_replay CORPUS_DIR          every target's folder
 *   fuzz_corpus_replay CORPUS_DIR TARGET   one of them */
#define _POSIX_C_SOURCE 200809L
#include "fuzz.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const struct {
    const char *name;
    int (*run)(const uint8_t *, size_t);
} targets[] = {
    {"pslg_io", fuzz_pslg_io},
    {"triangulate", fuzz_triangulate},
    {"heightfield", fuzz_heightfield},
    {"patch_io", fuzz_patch_io},
};

static int cmp(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Replays every regular file of dir; returns how many, or -1 on error. */
static long replay_dir(const char *dir, int (*run)(const uint8_t *, size_t))
{
    DIR *d = opendir(dir);
    if (!d) {
        fprintf(stderr, "fuzz_corpus_replay: cannot open %s\n", dir);
        return -1;
    }
    char **names = NULL;
    size_t n = 0, cap = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.')
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            char **grown = realloc(names, cap * sizeof *names);
            if (!grown)
                abort();
            names = grown;
        }
        if (!(names[n++] = strdup(e->d_name)))
            abort();
    }
    closedir(d);
    qsort(names, n, sizeof *names, cmp); /* the same order every run */
    long done = 0;
    for (size_t i = 0; i < n; i++) {
        char path[4096];
        struct stat st;
        if (snprintf(path, sizeof path, "%s/%s", dir, names[i]) >= (int)sizeof path)
            continue;
        FILE *f = stat(path, &st) == 0 && S_ISREG(st.st_mode) ? fopen(path, "rb") : NULL;
        if (f) {
            size_t len = (size_t)st.st_size;
            uint8_t *buf = malloc(len ? len : 1);
            if (!buf || fread(buf, 1, len, f) != len) {
                fprintf(stderr, "fuzz_corpus_replay: cannot read %s\n", path);
                abort();
            }
            fclose(f);
            fprintf(stderr, "%s\n", path); /* names the input if run() aborts */
            run(buf, len);
            free(buf);
            done++;
        }
        free(names[i]);
    }
    free(names);
    return done;
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: %s CORPUS_DIR [TARGET]\n", argv[0]);
        return 2;
    }
    int status = 0;
    bool any = false;
    for (size_t t = 0; t < sizeof targets / sizeof targets[0]; t++) {
        if (argc == 3 && strcmp(argv[2], targets[t].name) != 0)
            continue;
        any = true;
        char dir[4096];
        long n = snprintf(dir, sizeof dir, "%s/%s", argv[1], targets[t].name) < (int)sizeof dir
                     ? replay_dir(dir, targets[t].run)
                     : -1;
        if (n <= 0) {
            fprintf(stderr, "fuzz_corpus_replay: %s: %s\n", dir, n < 0 ? "unreadable" : "no inputs");
            status = 1;
        } else {
            printf("%s: %ld inputs replayed\n", targets[t].name, n);
        }
    }
    if (!any) {
        fprintf(stderr, "fuzz_corpus_replay: unknown target %s\n", argv[2]);
        return 2;
    }
    return status;
}

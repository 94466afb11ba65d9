/* bench_peers.c: other people's heightmap meshers, run by node on the same
 * heightfield for `tessera bench mesh --peers` (see bench.h). The peer
 * process lives as long as one input: it reads the heights once, then
 * answers one command per line (tools/peers/mesh_peer.mjs says how), and
 * writes each mesh to a file that is read back here into a tsr_mesh. */
#define _GNU_SOURCE /* readlink, mkdtemp */
#include "bench.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

struct bench_peer {
    pid_t pid;
    FILE *to, *from;
    char dir[PATH_MAX], heights[PATH_MAX + 16], out[PATH_MAX + 16];
    const tsr_heightfield *hf;
    uint32_t w, h;
    double dx, dy, dz;
};

static void say(char *why, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, n, fmt, ap);
    va_end(ap);
}

/* The script: $TSR_PEER_SCRIPT, else ../peers/mesh_peer.mjs beside the
 * binary (the build tree's copy, next to build/node_modules). */
static bool find_script(char *path, size_t n)
{
    const char *env = getenv("TSR_PEER_SCRIPT");
    if (env && *env) {
        snprintf(path, n, "%s", env);
        return access(path, R_OK) == 0;
    }
    char exe[PATH_MAX];
    ssize_t k = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (k <= 0)
        return false;
    exe[k] = 0;
    char *slash = strrchr(exe, '/');
    if (!slash)
        return false;
    static const char rel[] = "/../peers/mesh_peer.mjs";
    size_t dir = (size_t)(slash - exe);
    if (dir + sizeof rel > n)
        return false;
    memcpy(path, exe, dir);
    memcpy(path + dir, rel, sizeof rel);
    return access(path, R_OK) == 0;
}

static bool write_heights(const bench_peer *p, char *why, size_t n)
{
    FILE *f = fopen(p->heights, "wb");
    if (!f) {
        say(why, n, "%s: %s", p->heights, strerror(errno));
        return false;
    }
    const float *d = tsr_heightfield_cdata(p->hf);
    double *row = malloc(sizeof(double) * p->w);
    bool ok = row != NULL;
    for (uint32_t r = 0; ok && r < p->h; r++) {
        for (uint32_t c = 0; c < p->w; c++) {
            float v = d[(size_t)r * p->w + c];
            if (isnan(v)) {
                say(why, n, "the heightfield has no-data samples (the peers cannot leave holes)");
                ok = false;
                break;
            }
            row[c] = v * p->dz;
        }
        if (ok && fwrite(row, sizeof(double), p->w, f) != p->w) {
            say(why, n, "%s: %s", p->heights, strerror(errno));
            ok = false;
        }
    }
    if (!row)
        say(why, n, "out of memory");
    free(row);
    if (fclose(f) != 0 && ok) {
        say(why, n, "%s: %s", p->heights, strerror(errno));
        ok = false;
    }
    return ok;
}

bench_peer *bench_peer_start(const tsr_heightfield *hf, char *why, size_t n)
{
    char script[PATH_MAX];
    if (!find_script(script, sizeof script)) {
        say(why, n, "no peer script (%s; build the project, or set TSR_PEER_SCRIPT)",
            getenv("TSR_PEER_SCRIPT") ? getenv("TSR_PEER_SCRIPT") : "../peers/mesh_peer.mjs beside the binary");
        return NULL;
    }
    bench_peer *p = calloc(1, sizeof *p);
    if (!p) {
        say(why, n, "out of memory");
        return NULL;
    }
    p->pid = -1;
    p->hf = hf;
    p->w = tsr_heightfield_width(hf);
    p->h = tsr_heightfield_height(hf);
    tsr_heightfield_spacing(hf, &p->dx, &p->dy, &p->dz);
    const char *tmp = getenv("TMPDIR");
    snprintf(p->dir, sizeof p->dir, "%s/tessera-peer-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(p->dir)) {
        say(why, n, "%s: %s", p->dir, strerror(errno));
        free(p);
        return NULL;
    }
    snprintf(p->heights, sizeof p->heights, "%s/heights.f64", p->dir);
    snprintf(p->out, sizeof p->out, "%s/mesh.bin", p->dir);
    if (!write_heights(p, why, n)) {
        bench_peer_stop(p);
        return NULL;
    }
    /* a peer that dies must not take the bench with it */
    signal(SIGPIPE, SIG_IGN);
    int in[2], outp[2];
    if (pipe(in) != 0) {
        say(why, n, "pipe: %s", strerror(errno));
        bench_peer_stop(p);
        return NULL;
    }
    if (pipe(outp) != 0) {
        say(why, n, "pipe: %s", strerror(errno));
        close(in[0]);
        close(in[1]);
        bench_peer_stop(p);
        return NULL;
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, in[0], 0);
    posix_spawn_file_actions_adddup2(&fa, outp[1], 1);
    posix_spawn_file_actions_addclose(&fa, in[1]);
    posix_spawn_file_actions_addclose(&fa, outp[0]);
    char ws[16], hs[16];
    snprintf(ws, sizeof ws, "%u", p->w);
    snprintf(hs, sizeof hs, "%u", p->h);
    char *argv[] = {"node", "--expose-gc", script, p->heights, ws, hs, NULL};
    int rc = posix_spawnp(&p->pid, "node", &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    close(in[0]);
    close(outp[1]);
    if (rc != 0) {
        p->pid = -1;
        close(in[1]);
        close(outp[0]);
        say(why, n, "cannot run node: %s (tools/install-deps.sh installs it)", strerror(rc));
        bench_peer_stop(p);
        return NULL;
    }
    p->to = fdopen(in[1], "w");
    p->from = fdopen(outp[0], "r");
    if (!p->to || !p->from) {
        if (!p->to)
            close(in[1]);
        if (!p->from)
            close(outp[0]);
        say(why, n, "out of memory");
        bench_peer_stop(p);
        return NULL;
    }
    char line[256];
    if (!fgets(line, sizeof line, p->from) || strncmp(line, "ready", 5) != 0) {
        say(why, n, "the peer script did not start (node's message, if any, is above)");
        bench_peer_stop(p);
        return NULL;
    }
    return p;
}

/* Reads the mesh file back into mesh; positions at the samples. */
static bool read_mesh(bench_peer *p, uint32_t nv_said, uint32_t nt_said, tsr_mesh *mesh, char *why, size_t n)
{
    FILE *f = fopen(p->out, "rb");
    if (!f) {
        say(why, n, "%s: %s", p->out, strerror(errno));
        return false;
    }
    uint32_t head[2];
    bool ok = fread(head, sizeof head, 1, f) == 1 && head[0] == nv_said && head[1] == nt_said;
    uint32_t *v = NULL, *t = NULL;
    if (ok) {
        v = malloc(sizeof(uint32_t) * 2 * ((size_t)head[0] + 1));
        t = malloc(sizeof(uint32_t) * 3 * ((size_t)head[1] + 1));
        ok = v && t && fread(v, sizeof(uint32_t) * 2, head[0], f) == head[0] &&
             fread(t, sizeof(uint32_t) * 3, head[1], f) == head[1] && fgetc(f) == EOF;
    }
    fclose(f);
    if (!ok) {
        say(why, n, "%s: not the mesh the peer announced", p->out);
        free(v);
        free(t);
        return false;
    }
    const float *d = tsr_heightfield_cdata(p->hf);
    ok = tsr_mesh_reserve(mesh, head[0], head[1]) == TSR_OK;
    for (uint32_t i = 0; ok && i < head[0]; i++) {
        uint32_t c = v[2 * i], r = v[2 * i + 1];
        if (c >= p->w || r >= p->h) {
            say(why, n, "the peer's vertex %u (%u, %u) lies outside the %u x %u heightfield", i, c, r, p->w, p->h);
            ok = false;
            break;
        }
        float pos[3] = {(float)(c * p->dx), (float)(r * p->dy), (float)(d[(size_t)r * p->w + c] * p->dz)};
        ok = tsr_mesh_add_vertex(mesh, pos, NULL, NULL) != UINT32_MAX;
    }
    /* counter-clockwise seen from +z in the output's (x, y) */
    double flip = p->dx * p->dy < 0 ? -1 : 1;
    for (uint32_t i = 0; ok && i < head[1]; i++) {
        uint32_t a = t[3 * i], b = t[3 * i + 1], c = t[3 * i + 2];
        if (a >= head[0] || b >= head[0] || c >= head[0]) {
            say(why, n, "the peer's triangle %u names a vertex beyond its %u", i, head[0]);
            ok = false;
            break;
        }
        double ax = v[2 * a], ay = v[2 * a + 1];
        double cross = (v[2 * b] - ax) * (v[2 * c + 1] - ay) - (v[2 * b + 1] - ay) * (v[2 * c] - ax);
        ok = cross * flip >= 0 ? tsr_mesh_add_triangle(mesh, a, b, c) : tsr_mesh_add_triangle(mesh, a, c, b);
    }
    if (!ok && !*why)
        say(why, n, "out of memory for the peer's mesh");
    free(v);
    free(t);
    return ok;
}

bool bench_peer_mesh(bench_peer *p, const char *method, double e, uint32_t repeat, tsr_mesh *mesh,
                     bench_peer_run *run, char *why, size_t n)
{
    *why = 0;
    memset(run, 0, sizeof *run);
    if (fprintf(p->to, "%s %.17g %u %s\n", method, e, repeat, p->out) < 0 || fflush(p->to) != 0) {
        say(why, n, "the peer process has gone");
        return false;
    }
    char line[1024];
    if (!fgets(line, sizeof line, p->from)) {
        say(why, n, "the peer process has gone (node's message, if any, is above)");
        return false;
    }
    line[strcspn(line, "\n")] = 0;
    if (!strncmp(line, "error ", 6)) {
        say(why, n, "%s", line + 6);
        return false;
    }
    unsigned nv, nt;
    double s, live;
    if (sscanf(line, "ok %u %u %lf %lf", &nv, &nt, &s, &live) != 4) {
        say(why, n, "the peer answered '%s'", line);
        return false;
    }
    run->vertices = nv;
    run->triangles = nt;
    run->seconds = s;
    run->live_bytes = live;
    return read_mesh(p, nv, nt, mesh, why, n);
}

void bench_peer_stop(bench_peer *p)
{
    if (!p)
        return;
    if (p->to) {
        fprintf(p->to, "quit\n");
        fclose(p->to);
    }
    if (p->from) {
        char line[256];
        while (fgets(line, sizeof line, p->from))
            ;
        fclose(p->from);
    }
    if (p->pid > 0) {
        int st;
        while (waitpid(p->pid, &st, 0) < 0 && errno == EINTR)
            ;
    }
    if (p->heights[0])
        unlink(p->heights);
    if (p->out[0])
        unlink(p->out);
    if (p->dir[0])
        rmdir(p->dir);
    free(p);
}

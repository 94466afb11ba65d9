/* cmd_fly.c: `tessera fly IN`: a real-time flyover of a heightfield, in a
 * window (GLFW) or headless along a path into numbered PNGs. */
#define _POSIX_C_SOURCE 200809L
#include "fly.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera fly IN [options]\n\n"
               "Flies over a heightfield drawn by the GPU (Vulkan; Mesa's lavapipe where there is no GPU):\n"
               "a restricted quadtree of grid tiles chosen each frame so that no sample is more than the\n"
               "pixel error off screen, crack-free, with geomorphing.\n\n"
               "In a window: mouse (hold the left button) looks around, W A S D fly, Q and E go down and up,\n"
               "Shift goes faster, + and - raise and lower the pixel error, F toggles the wireframe (tile\n"
               "borders white, levels in colour), G toggles geomorphing, N shows the shading normals as\n"
               "colours, Esc quits. The title bar shows frame time, tiles, triangles, pixel error and MB\n"
               "resident.\n\n"
               "options:\n"
               "  --headless            render offscreen along the flight path instead of a window\n"
               "  --frames N            headless: frames to render (default 120); window: quit after N\n"
               "  --out DIR             headless: where the frames go, DIR/frame_00000.png ... (default\n"
               "                        fly-frames); a run that fails or is interrupted leaves DIR as it was\n"
               "  --video FILE.mp4      headless: assemble the frames with ffmpeg (30 fps, MP4; refused before\n"
               "                        rendering when ffmpeg is not installed)\n"
               "  --path FILE           keyframes, one per line: EX EY EZ [TX TY TZ] (world units); default: an\n"
               "                        automatic loop over the terrain; one keyframe: a still camera (looking\n"
               "                        at its target, else the terrain's centre); cameras are kept above the\n"
               "                        ground (a path's too: a note says how many were raised)\n"
               "  --width W, --height H viewport in pixels (default 1280 x 720)\n"
               "  --pixel-error T       screen-space error allowed, pixels, up to 10000 (default 2)\n"
               "  --tile N              tile size: 2, 4, ..., 128 quads (default 16)\n"
               "  --fov DEG             vertical field of view, 1 to 170 degrees (default 60)\n"
               "  --fog D               haze: the distance at which the sky's colour reaches 63 %%, in world\n"
               "                        units; 0: none (default: a third of the terrain's diagonal)\n"
               "  --wireframe           start with the wireframe overlay\n"
               "  --no-geomorph         start without geomorphing\n"
               "  --show-normals        draw the shading normals as colours (x red, y green, z blue), unlit\n"
               "  --cache MB            resident tile budget (default 256); a view whose tiles do not fit is\n"
               "                        drawn at a coarser pixel error, and a note says so\n"
               "  --device NAME|INDEX   the Vulkan device (default: TESSERA_VK_DEVICE, else a discrete GPU,\n"
               "                        then integrated, then lavapipe)\n"
               "  --stats FILE.json     per-frame select, upload, record, draw and wait times, tiles, triangles\n"
               "                        and uploaded bytes\n"
               "  --quiet               no progress\n" CLI_HEIGHTFIELD_HELP "  -h, --help            this help\n");
}

typedef struct frame_rec {
    double select_ms, upload_ms, record_ms, gpu_ms, wait_ms, frame_ms;
    double pixel_error; /* of the cut drawn: above the option's when the cache made it coarser */
    uint32_t tiles, uploaded;
    uint64_t triangles, gpu_triangles, bytes_uploaded, bytes_resident;
} frame_rec;

typedef struct fly_args {
    const char *in, *out_dir, *video, *path_file, *stats, *device;
    bool headless, quiet;
    uint32_t frames, width, height;
    fly_options o;
} fly_args;

/* used: the options as fly_init completed them (defaults filled in) */
static cJSON *stats_json(const fly_args *a, const fly_options *used, const char *device, const frame_rec *r,
                         uint32_t n)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "input", a->in);
    cJSON_AddStringToObject(root, "device", device);
    cJSON_AddNumberToObject(root, "width", a->width);
    cJSON_AddNumberToObject(root, "height", a->height);
    cJSON_AddNumberToObject(root, "tile", used->tile_n);
    cJSON_AddNumberToObject(root, "pixel_error", used->pixel_error);
    cJSON_AddNumberToObject(root, "near", used->near_dist);
    cJSON *frames = cJSON_AddArrayToObject(root, "frames");
    double sum[6] = {0};
    for (uint32_t i = 0; i < n; i++) {
        cJSON *f = cJSON_CreateObject();
        cJSON_AddNumberToObject(f, "select_ms", r[i].select_ms);
        cJSON_AddNumberToObject(f, "upload_ms", r[i].upload_ms);
        cJSON_AddNumberToObject(f, "record_ms", r[i].record_ms);
        cJSON_AddNumberToObject(f, "draw_ms", r[i].gpu_ms);
        cJSON_AddNumberToObject(f, "wait_ms", r[i].wait_ms);
        cJSON_AddNumberToObject(f, "frame_ms", r[i].frame_ms);
        cJSON_AddNumberToObject(f, "pixel_error", r[i].pixel_error);
        cJSON_AddNumberToObject(f, "tiles", r[i].tiles);
        cJSON_AddNumberToObject(f, "tiles_uploaded", r[i].uploaded);
        cJSON_AddNumberToObject(f, "triangles", (double)r[i].triangles);
        cJSON_AddNumberToObject(f, "gpu_triangles", (double)r[i].gpu_triangles);
        cJSON_AddNumberToObject(f, "uploaded_bytes", (double)r[i].bytes_uploaded);
        cJSON_AddNumberToObject(f, "resident_bytes", (double)r[i].bytes_resident);
        cJSON_AddItemToArray(frames, f);
        double v[6] = {r[i].select_ms, r[i].upload_ms, r[i].record_ms, r[i].gpu_ms, r[i].wait_ms, r[i].frame_ms};
        for (int k = 0; k < 6; k++)
            sum[k] += v[k];
    }
    cJSON *mean = cJSON_AddObjectToObject(root, "mean");
    const char *names[6] = {"select_ms", "upload_ms", "record_ms", "draw_ms", "wait_ms", "frame_ms"};
    for (int k = 0; k < 6; k++)
        cJSON_AddNumberToObject(mean, names[k], n ? sum[k] / n : 0);
    return root;
}

static int write_stats(const fly_args *a, const fly_options *used, const char *device, const frame_rec *r, uint32_t n)
{
    if (!a->stats)
        return CLI_OK;
    cJSON *root = stats_json(a, used, device, r, n);
    char *text = root ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (!text) {
        cli_error("fly", "out of memory writing %s", a->stats);
        return CLI_FAIL;
    }
    tsr_error err = {0};
    tsr_status st = cli_write_text(a->stats, text, &err);
    free(text);
    if (st != TSR_OK) {
        cli_error("fly", "%s", err.message);
        return CLI_FAIL;
    }
    return CLI_OK;
}

static void record(frame_rec *rec, const fly_frame_stats *fs, double frame_ms)
{
    rec->select_ms = fs->select_ms;
    rec->pixel_error = fs->pixel_error;
    rec->upload_ms = fs->render.upload_ms;
    rec->record_ms = fs->render.record_ms;
    rec->gpu_ms = fs->render.device.gpu_ms;
    rec->wait_ms = fs->render.device.submit_wait_ms;
    rec->frame_ms = frame_ms;
    rec->tiles = fs->render.tiles;
    rec->uploaded = fs->render.tiles_uploaded;
    rec->triangles = fs->render.triangles;
    rec->gpu_triangles = fs->render.device.triangles;
    rec->bytes_uploaded = fs->render.bytes_uploaded;
    rec->bytes_resident = fs->render.bytes_resident;
}

/* A note on the frames whose cut did not fit the tile cache at the pixel
 * error asked, and were drawn coarser. */
static void note_coarsened(const fly_options *used, const frame_rec *r, uint32_t n)
{
    uint32_t count = 0, first = 0;
    double worst = 0;
    for (uint32_t i = 0; i < n; i++)
        if (r[i].pixel_error > used->pixel_error) {
            if (!count++)
                first = i;
            worst = fmax(worst, r[i].pixel_error);
        }
    if (count)
        fprintf(stderr, "tessera fly: note: %u of %u frames (the first: frame %u) needed more tiles than the cache of "
                "%.0f MB holds at %g px; they were drawn coarser, at up to %.3g px (a larger --cache keeps the pixel "
                "error)\n", count, n, first, (double)used->cache_bytes / 1048576.0, used->pixel_error, worst);
}

static bool make_dir(const char *dir)
{
    char buf[4096];
    size_t n = strlen(dir);
    if (n == 0 || n >= sizeof buf)
        return false;
    memcpy(buf, dir, n + 1);
    for (size_t i = 1; i <= n; i++)
        if (buf[i] == '/' || buf[i] == 0) {
            char c = buf[i];
            buf[i] = 0;
            if (mkdir(buf, 0777) != 0 && errno != EEXIST)
                return false;
            buf[i] = c;
        }
    struct stat sb;
    if (stat(dir, &sb) != 0)
        return false;
    if (!S_ISDIR(sb.st_mode))
        errno = ENOTDIR;
    return S_ISDIR(sb.st_mode);
}

/* make_dir for --out, saying why when it fails. */
static bool make_out_dir(const char *dir)
{
    if (make_dir(dir))
        return true;
    if (errno == ENOTDIR || errno == EEXIST)
        cli_error("fly", "--out %s: a file of that name is in the way (--out names a folder for the frames)", dir);
    else
        cli_error("fly", "cannot create the output folder %s: %s", dir, strerror(errno));
    return false;
}

/* path made absolute against the working folder, with repeated slashes,
 * "." and ".." resolved by name (links are not followed), in buf; false
 * when it does not fit. */
static bool lexical_path(const char *path, char *buf, size_t cap)
{
    char in[8192];
    if (path[0] == '/') {
        if (snprintf(in, sizeof in, "%s", path) >= (int)sizeof in)
            return false;
    } else {
        char cwd[4096];
        if (!getcwd(cwd, sizeof cwd) || snprintf(in, sizeof in, "%s/%s", cwd, path) >= (int)sizeof in)
            return false;
    }
    size_t n = 0;
    for (const char *p = in; *p;) {
        while (*p == '/')
            p++;
        const char *q = p;
        while (*q && *q != '/')
            q++;
        size_t len = (size_t)(q - p);
        if (len == 2 && p[0] == '.' && p[1] == '.') {
            while (n > 0 && buf[n - 1] != '/')
                n--;
            if (n > 0)
                n--; /* the slash before the dropped name */
        } else if (len && !(len == 1 && p[0] == '.')) {
            if (n + 1 + len + 1 > cap)
                return false;
            buf[n++] = '/';
            memcpy(buf + n, p, len);
            n += len;
        }
        p = q;
    }
    if (n == 0)
        buf[n++] = '/';
    buf[n] = 0;
    return true;
}

/* Does path lie inside folder dir (by name)? */
static bool inside_folder(const char *path, const char *dir)
{
    char p[4096], d[4096];
    if (!lexical_path(path, p, sizeof p) || !lexical_path(dir, d, sizeof d))
        return false;
    size_t nd = strlen(d);
    return !strncmp(p, d, nd) && (p[nd] == '/' || (nd == 1 && d[0] == '/'));
}

static bool have_program(const char *name)
{
    const char *path = getenv("PATH");
    if (!path)
        return false;
    char buf[4096];
    while (*path) {
        const char *colon = strchr(path, ':');
        size_t len = colon ? (size_t)(colon - path) : strlen(path);
        if (len && len + strlen(name) + 2 < sizeof buf) {
            memcpy(buf, path, len);
            buf[len] = '/';
            strcpy(buf + len + 1, name);
            if (access(buf, X_OK) == 0)
                return true;
        }
        path += len + (colon ? 1 : 0);
    }
    return false;
}

/* Runs ffmpeg (run_headless checked it is there) on the frames into a
 * temporary beside `video`, renamed when complete. */
static int assemble_video(const fly_args *a)
{
    char pattern[4200], tmp[4200], count[32];
    snprintf(pattern, sizeof pattern, "%s/frame_%%05d.png", a->out_dir);
    snprintf(tmp, sizeof tmp, "%s.tmp-%ld.mp4", a->video, (long)getpid());
    snprintf(count, sizeof count, "%u", a->frames);
    pid_t pid = fork();
    if (pid == 0) {
        execlp("ffmpeg", "ffmpeg", "-y", "-loglevel", "error", "-framerate", "30", "-i", pattern, "-frames:v", count,
               "-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4", tmp, (char *)NULL);
        _exit(127);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        unlink(tmp);
        cli_error("fly", "ffmpeg failed to make %s from %s", a->video, pattern);
        return CLI_FAIL;
    }
    if (rename(tmp, a->video) != 0) {
        unlink(tmp);
        cli_error("fly", "%s: %s", a->video, strerror(errno));
        return CLI_FAIL;
    }
    return CLI_OK;
}

/* Removes out_dir/frame_NNNNN.png for N >= from: the frames of an earlier,
 * longer run. */
static void remove_frames(const char *out_dir, uint32_t from)
{
    DIR *d = opendir(out_dir);
    if (!d)
        return;
    struct dirent *e;
    while ((e = readdir(d))) {
        /* frame_ and at least five digits (more only without a leading 0), .png */
        const char *p = e->d_name, *q;
        if (strncmp(p, "frame_", 6) != 0)
            continue;
        uint64_t n = 0;
        for (q = p + 6; *q >= '0' && *q <= '9' && q - p < 16; q++)
            n = n * 10 + (uint64_t)(*q - '0');
        size_t nd = (size_t)(q - p - 6);
        if (nd < 5 || (nd > 5 && p[6] == '0') || strcmp(q, ".png") != 0 || n < from)
            continue;
        char name[4200];
        snprintf(name, sizeof name, "%s/%s", out_dir, e->d_name);
        unlink(name);
    }
    closedir(d);
}

/* A run's frames go into a hidden folder inside --out and are moved into
 * --out when every one is drawn, so a run that fails or is interrupted
 * leaves --out as it was: an earlier flight's frames whole, none of this
 * run's among them. On a signal, cli_signal_cleanup removes the staged
 * frames (only async-signal-safe calls: the names are built by hand). */
static char stage_dir[4096];
static volatile sig_atomic_t stage_count; /* frames 0 .. stage_count - 1 are staged */

/* dir/frame_NNNNN.png (at least five digits, as "%05u") into buf. */
static void frame_path(char *buf, size_t cap, const char *dir, uint32_t i)
{
    char digits[16];
    int nd = 0;
    do {
        digits[nd++] = (char)('0' + i % 10);
        i /= 10;
    } while (i || nd < 5);
    size_t len = strlen(dir);
    if (len + 12 + (size_t)nd >= cap) {
        buf[0] = 0;
        return;
    }
    memcpy(buf, dir, len);
    memcpy(buf + len, "/frame_", 7);
    len += 7;
    while (nd)
        buf[len++] = digits[--nd];
    memcpy(buf + len, ".png", 5);
}

static void unstage(void)
{
    if (!stage_dir[0])
        return;
    char name[4200];
    /* stage_count itself too: the frame being written may be in place
     * before the count says so */
    for (uint32_t i = 0; i <= (uint32_t)stage_count; i++) {
        frame_path(name, sizeof name, stage_dir, i);
        unlink(name);
    }
    rmdir(stage_dir);
    stage_dir[0] = 0;
}

/* The staged frames into out_dir (replacing those of the same numbers);
 * unstage then removes the emptied folder. */
static bool unstage_into(const char *out_dir, uint32_t n, tsr_error *err)
{
    char from[4200], to[4200];
    for (uint32_t i = 0; i < n; i++) {
        frame_path(from, sizeof from, stage_dir, i);
        frame_path(to, sizeof to, out_dir, i);
        if (rename(from, to) != 0)
            return tsr_error_set(err, TSR_ERR_IO, "%s: %s", to, strerror(errno)), false;
    }
    stage_count = 0;
    return true;
}

static int run_headless(fly_args *a, const tsr_heightfield *hf)
{
    if (a->video && !have_program("ffmpeg")) { /* before the work, not after it */
        cli_error("fly", "--video %s: ffmpeg is not installed (apt install ffmpeg), so no video can be made", a->video);
        return CLI_FAIL;
    }
    tsr_hw_vulkan_options vo = {.width = a->width, .height = a->height, .device = a->device};
    tsr_hw_backend *be = NULL;
    tsr_error err = {0};
    if (tsr_hw_vulkan_create(&vo, NULL, &be, &err) != TSR_OK) {
        cli_error("fly", "%s", err.message);
        return CLI_FAIL;
    }
    fly_ctx f;
    if (fly_init(&f, hf, be, &a->o, &err) != TSR_OK) {
        cli_error("fly", "%s: %s", a->in, err.message);
        be->destroy(be);
        return CLI_FAIL;
    }
    fly_path path;
    tsr_status st = a->path_file ? fly_path_read(a->path_file, &path, &err) : fly_path_auto(&f, &path, &err);
    int rc = CLI_OK;
    frame_rec *recs = calloc(a->frames, sizeof *recs);
    tsr_camera *cams = malloc((a->frames ? a->frames : 1) * sizeof *cams);
    uint8_t *rgba = malloc((size_t)a->width * a->height * 4);
    if (st != TSR_OK || !recs || !cams || !rgba) {
        cli_error("fly", "%s", st != TSR_OK ? err.message : "out of memory");
        rc = CLI_FAIL;
        goto done;
    }
    if (!make_out_dir(a->out_dir)) {
        rc = CLI_FAIL;
        goto done;
    }
    errno = 0;
    if (snprintf(stage_dir, sizeof stage_dir, "%s/.tessera-fly-XXXXXX", a->out_dir) >= (int)sizeof stage_dir ||
        !mkdtemp(stage_dir)) {
        cli_error("fly", "cannot create a folder for the frames in %s: %s", a->out_dir,
                  errno ? strerror(errno) : "the name is too long");
        stage_dir[0] = 0;
        rc = CLI_FAIL;
        goto done;
    }
    stage_count = 0;
    cli_signal_cleanup = unstage;
    double clearance = 0.01 * (f.zmax - f.zmin) + 2 * f.o.near_dist;
    bool tty = !a->quiet && isatty(2);
    double t_start = cli_now();
    /* every frame's camera, before any frame is written */
    uint32_t lifted = 0, first_lifted = 0;
    for (uint32_t i = 0; i < a->frames; i++) {
        double s = path.closed ? (double)i / a->frames : a->frames > 1 ? (double)i / (a->frames - 1) : 0;
        bool low = false;
        if (!fly_path_camera(&f, &path, s, clearance, &cams[i], &low)) {
            if (path.count == 1 && !path.target)
                cli_error("fly",
                          "%s: the keyframe's eye is the terrain's centre, which a keyframe without a "
                          "target looks at: give it a target (EX EY EZ TX TY TZ)",
                          a->path_file);
            else
                cli_error("fly", "%s: frame %u: the camera is degenerate (the target at the eye, or no view)",
                          a->path_file ? a->path_file : "the automatic path", i);
            rc = CLI_FAIL;
            goto done;
        }
        if (low && !lifted++)
            first_lifted = i;
    }
    if (lifted && a->path_file && !a->quiet)
        fprintf(stderr,
                "tessera fly: note: %s: %u of %u cameras (the first at frame %u) were less than %g above "
                "the ground; they were raised to %g above it\n",
                a->path_file, lifted, a->frames, first_lifted, clearance, clearance);
    for (uint32_t i = 0; i < a->frames; i++) {
        double t0 = cli_now();
        fly_frame_stats fs;
        if (fly_frame(&f, &cams[i], &fs, &err) != TSR_OK) {
            cli_error("fly", "frame %u: %s", i, err.message);
            rc = CLI_FAIL;
            goto done;
        }
        record(&recs[i], &fs, (cli_now() - t0) * 1e3);
        char name[4200];
        frame_path(name, sizeof name, stage_dir, i);
        if (!be->read_color(be, rgba) || tsr_image_save_u8(name, a->width, a->height, 4, rgba, &err) != TSR_OK) {
            cli_error("fly", "%s", err.message[0] ? err.message : "cannot read the frame back");
            rc = CLI_FAIL;
            goto done;
        }
        stage_count = (sig_atomic_t)(i + 1);
        if (tty)
            fprintf(stderr, "\rtessera fly: frame %u/%u (%.1f ms, %u tiles, %llu triangles)   ", i + 1, a->frames,
                    recs[i].frame_ms, recs[i].tiles, (unsigned long long)recs[i].triangles);
    }
    if (tty)
        fprintf(stderr, "\n");
    if (be->stats.validation_messages) {
        cli_error("fly", "the Vulkan validation layers reported %llu message(s)",
                  (unsigned long long)be->stats.validation_messages);
        rc = CLI_FAIL;
    }
    if (!a->quiet)
        note_coarsened(&f.o, recs, a->frames);
    if (!a->quiet) {
        double ms = 0;
        for (uint32_t i = 0; i < a->frames; i++)
            ms += recs[i].frame_ms;
        fprintf(stderr, "tessera fly: %u frames on %s in %.1f s (%.1f ms per frame to draw), in %s/\n", a->frames,
                be->name, cli_now() - t_start, a->frames ? ms / a->frames : 0, a->out_dir);
    }
    uint32_t drawn = 0;
    for (uint32_t i = 0; i < a->frames; i++)
        drawn += recs[i].tiles > 0;
    if (!drawn) /* a warning, even with --quiet: the images show only sky */
        fprintf(stderr,
                "tessera fly: warning: no frame shows any of the terrain (no tile in view); the cameras look "
                "away from it or are too far%s\n",
                a->path_file ? ": check the path's eyes and targets" : "");
    if (rc == CLI_OK)
        rc = write_stats(a, &f.o, be->name, recs, a->frames);
    if (rc == CLI_OK && !unstage_into(a->out_dir, a->frames, &err)) {
        cli_error("fly", "%s", err.message);
        rc = CLI_FAIL;
    }
    if (rc == CLI_OK) /* a longer earlier run's frames would read as this flight's */
        remove_frames(a->out_dir, a->frames);
    if (rc == CLI_OK && a->video)
        rc = assemble_video(a); /* on failure the frames stay: ffmpeg can be run on them by hand */
done:
    unstage();
    cli_signal_cleanup = NULL;
    free(recs);
    free(cams);
    free(rgba);
    fly_path_free(&path);
    fly_free(&f);
    be->destroy(be);
    return rc;
}

/* ---- the window --------------------------------------------------------------- */

typedef struct window_state {
    double yaw, pitch, last_x, last_y;
    bool looking, have_last;
} window_state;

static void key_cb(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    (void)mods;
    fly_ctx *f = glfwGetWindowUserPointer(w);
    if (action != GLFW_PRESS && action != GLFW_REPEAT)
        return;
    if (key == GLFW_KEY_ESCAPE)
        glfwSetWindowShouldClose(w, GLFW_TRUE);
    else if (key == GLFW_KEY_F && action == GLFW_PRESS)
        f->o.wireframe = !f->o.wireframe;
    else if (key == GLFW_KEY_G && action == GLFW_PRESS)
        f->o.geomorph = !f->o.geomorph;
    else if (key == GLFW_KEY_N && action == GLFW_PRESS)
        f->o.show_normals = !f->o.show_normals;
    else if (key == GLFW_KEY_EQUAL || key == GLFW_KEY_KP_ADD)
        f->o.pixel_error = fmin(f->o.pixel_error * 1.25, 64);
    else if (key == GLFW_KEY_MINUS || key == GLFW_KEY_KP_SUBTRACT)
        f->o.pixel_error = fmax(f->o.pixel_error / 1.25, 0.25);
}

static int run_window(fly_args *a, const tsr_heightfield *hf)
{
    if (!glfwInit()) {
        cli_error("fly", "cannot open a window (no display?); use --headless to render frames offscreen");
        return CLI_FAIL;
    }
    if (!glfwVulkanSupported()) {
        glfwTerminate();
        cli_error("fly", "no Vulkan loader or driver for windows; install libvulkan1 and mesa-vulkan-drivers");
        return CLI_FAIL;
    }
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    GLFWwindow *win = glfwCreateWindow((int)a->width, (int)a->height, "tessera fly", NULL, NULL);
    if (!win) {
        glfwTerminate();
        cli_error("fly", "cannot create a %ux%u window", a->width, a->height);
        return CLI_FAIL;
    }
    tsr_hw_vulkan_options vo = {.width = a->width, .height = a->height, .device = a->device, .window = win};
    tsr_hw_backend *be = NULL;
    tsr_error err = {0};
    int rc = CLI_OK;
    if (tsr_hw_vulkan_create(&vo, NULL, &be, &err) != TSR_OK) {
        cli_error("fly", "%s", err.message);
        glfwDestroyWindow(win);
        glfwTerminate();
        return CLI_FAIL;
    }
    fly_ctx f;
    if (fly_init(&f, hf, be, &a->o, &err) != TSR_OK) {
        cli_error("fly", "%s: %s", a->in, err.message);
        be->destroy(be);
        glfwDestroyWindow(win);
        glfwTerminate();
        return CLI_FAIL;
    }
    glfwSetWindowUserPointer(win, &f);
    glfwSetKeyCallback(win, key_cb);
    /* start where the automatic path starts */
    fly_path path = {0};
    tsr_camera cam;
    double eye[3], yaw = 0, pitch = -0.2;
    if ((a->path_file ? fly_path_read(a->path_file, &path, &err) : fly_path_auto(&f, &path, &err)) == TSR_OK &&
        fly_path_camera(&f, &path, 0, 1, &cam, NULL)) {
        memcpy(eye, cam.eye, sizeof eye);
        yaw = atan2(cam.fwd[1], cam.fwd[0]);
        pitch = asin(fmax(-0.99, fmin(0.99, cam.fwd[2])));
    } else {
        eye[0] = eye[1] = 0;
        eye[2] = f.zmax + 10;
    }
    fly_path_free(&path);
    double extent = fmax((tsr_heightfield_width(hf) - 1) * f.dx, (tsr_heightfield_height(hf) - 1) * f.dy);
    double last = cli_now(), title_at = 0, last_x = 0, last_y = 0;
    bool have_cursor = false;
    frame_rec *recs = NULL;
    uint32_t nrec = 0, caprec = 0;
    while (!glfwWindowShouldClose(win) && (!a->frames || nrec < a->frames)) {
        glfwPollEvents();
        double now = cli_now(), dt = fmin(now - last, 0.1);
        last = now;
        double cx, cy;
        glfwGetCursorPos(win, &cx, &cy);
        if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
            if (have_cursor) {
                yaw += (cx - last_x) * 0.003; /* the screen is mirrored (fly_frame_desc): right turns right */
                pitch = fmax(-1.5, fmin(1.5, pitch - (cy - last_y) * 0.003));
            }
            have_cursor = true;
        } else
            have_cursor = false;
        last_x = cx;
        last_y = cy;
        double fwd[3] = {cos(pitch) * cos(yaw), cos(pitch) * sin(yaw), sin(pitch)};
        double right[2] = {-sin(yaw), cos(yaw)}; /* on the mirrored screen, the map's right */
        double speed = extent * 0.05 * dt * (glfwGetKey(win, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ? 5 : 1);
        int kw = glfwGetKey(win, GLFW_KEY_W) == GLFW_PRESS, ks = glfwGetKey(win, GLFW_KEY_S) == GLFW_PRESS;
        int ka = glfwGetKey(win, GLFW_KEY_A) == GLFW_PRESS, kd = glfwGetKey(win, GLFW_KEY_D) == GLFW_PRESS;
        int kq = glfwGetKey(win, GLFW_KEY_Q) == GLFW_PRESS, ke = glfwGetKey(win, GLFW_KEY_E) == GLFW_PRESS;
        for (int c = 0; c < 3; c++)
            eye[c] += speed * (kw - ks) * fwd[c];
        eye[0] += speed * (kd - ka) * right[0];
        eye[1] += speed * (kd - ka) * right[1];
        eye[2] += speed * (ke - kq);
        double g = ground_height(f.terrain, eye[0], eye[1]);
        if (!isnan(g) && eye[2] < g + 2 * f.o.near_dist)
            eye[2] = g + 2 * f.o.near_dist;
        double target[3] = {eye[0] + fwd[0], eye[1] + fwd[1], eye[2] + fwd[2]};
        if (!fly_camera(&f, eye, target, &cam))
            continue;
        fly_frame_stats fs;
        double t0 = cli_now();
        if (fly_frame(&f, &cam, &fs, &err) != TSR_OK) {
            cli_error("fly", "%s", err.message);
            rc = CLI_FAIL;
            break;
        }
        if (nrec == caprec) {
            caprec = caprec ? caprec * 2 : 256;
            frame_rec *nr = realloc(recs, caprec * sizeof *nr);
            if (!nr) {
                rc = CLI_FAIL;
                break;
            }
            recs = nr;
        }
        record(&recs[nrec++], &fs, (cli_now() - t0) * 1e3);
        if (now - title_at > 0.25) {
            title_at = now;
            char title[256];
            snprintf(title, sizeof title,
                     "tessera fly - %.1f ms - %u tiles - %.0fk triangles - tau %.2f px%s - %.0f MB resident%s%s%s",
                     recs[nrec - 1].frame_ms, fs.render.tiles, fs.render.triangles / 1e3, fs.pixel_error,
                     fs.coarsened ? " (coarser: the cache is full)" : "",
                     fs.render.bytes_resident / 1048576.0, f.o.wireframe ? " - wireframe" : "",
                     f.o.geomorph ? "" : " - no geomorph", f.o.show_normals ? " - normals" : "");
            glfwSetWindowTitle(win, title);
        }
    }
    if (be->stats.validation_messages) {
        cli_error("fly", "the Vulkan validation layers reported %llu message(s)",
                  (unsigned long long)be->stats.validation_messages);
        rc = CLI_FAIL;
    }
    if (rc == CLI_OK)
        rc = write_stats(a, &f.o, be->name, recs, nrec);
    if (!a->quiet)
        fprintf(stderr, "tessera fly: %u frames on %s\n", nrec, be->name);
    if (!a->quiet)
        note_coarsened(&f.o, recs, nrec);
    free(recs);
    fly_free(&f);
    be->destroy(be);
    glfwDestroyWindow(win);
    glfwTerminate();
    return rc;
}

static int run(int argc, char **argv)
{
    fly_args a = {.out_dir = "fly-frames", .width = 1280, .height = 720};
    a.o.geomorph = true;
    cli_heightfield_options ho = {0};
    bool frames_given = false, out_given = false;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        int h = cli_heightfield_option("fly", argc, argv, &i, &ho);
        if (h < 0)
            return CLI_USAGE;
        if (h > 0)
            continue;
        bool more = i + 1 < argc;
        if (cli_is_help(arg)) {
            help(stdout);
            return CLI_OK;
        } else if (!strcmp(arg, "--headless"))
            a.headless = true;
        else if (!strcmp(arg, "--quiet"))
            a.quiet = true;
        else if (!strcmp(arg, "--wireframe"))
            a.o.wireframe = true;
        else if (!strcmp(arg, "--no-geomorph"))
            a.o.geomorph = false;
        else if (!strcmp(arg, "--show-normals"))
            a.o.show_normals = true;
        else if (!strcmp(arg, "--frames") && more) {
            if (!cli_parse_u32(argv[++i], 1, 1000000, &a.frames)) {
                cli_error("fly", "--frames wants a count from 1 to 1000000, not '%s'", argv[i]);
                return CLI_USAGE;
            }
            frames_given = true;
        } else if ((!strcmp(arg, "--width") || !strcmp(arg, "--height")) && more) {
            uint32_t v;
            if (!cli_parse_u32(argv[++i], 16, 8192, &v)) {
                cli_error("fly", "%s wants pixels from 16 to 8192, not '%s'", arg, argv[i]);
                return CLI_USAGE;
            }
            *(arg[2] == 'w' ? &a.width : &a.height) = v;
        } else if (!strcmp(arg, "--pixel-error") && more) {
            if (!cli_parse_double(argv[++i], &a.o.pixel_error) || !(a.o.pixel_error > 0) || a.o.pixel_error > 1e4) {
                cli_error("fly", "--pixel-error wants pixels > 0, up to 10000, not '%s'", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(arg, "--fov") && more) {
            if (!cli_parse_double(argv[++i], &a.o.fovy_deg) || !(a.o.fovy_deg >= 1 && a.o.fovy_deg <= 170)) {
                cli_error("fly", "--fov wants degrees from 1 to 170, not '%s'", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(arg, "--tile") && more) {
            if (!cli_parse_u32(argv[++i], TSR_TILE_MIN, TSR_TILE_MAX, &a.o.tile_n) || !cli_tile_size_ok(a.o.tile_n)) {
                cli_error("fly", "--tile wants a power of two from 2 to 128, not '%s'", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(arg, "--cache") && more) {
            uint32_t mb;
            if (!cli_parse_u32(argv[++i], 1, 1 << 20, &mb)) {
                cli_error("fly", "--cache wants megabytes from 1, not '%s'", argv[i]);
                return CLI_USAGE;
            }
            a.o.cache_bytes = (uint64_t)mb << 20;
        } else if (!strcmp(arg, "--fog") && more) {
            double d;
            if (!cli_parse_double(argv[++i], &d) || !(d >= 0) || d > 1e15) {
                cli_error("fly", "--fog wants a distance from 0 (no fog) to 1e15 world units, not '%s'", argv[i]);
                return CLI_USAGE;
            }
            a.o.fog_distance = d > 0 ? d : -1;
        } else if (!strcmp(arg, "--out") && more) {
            a.out_dir = argv[++i];
            out_given = true;
        } else if (!strcmp(arg, "--video") && more)
            a.video = argv[++i];
        else if (!strcmp(arg, "--path") && more)
            a.path_file = argv[++i];
        else if (!strcmp(arg, "--stats") && more)
            a.stats = argv[++i];
        else if (!strcmp(arg, "--device") && more)
            a.device = argv[++i];
        else if (arg[0] == '-' && arg[1]) {
            cli_option_error("fly", NULL, arg, help);
            return CLI_USAGE;
        } else if (!a.in)
            a.in = arg;
        else {
            cli_error("fly", "one input only ('%s' and '%s')", a.in, arg);
            return CLI_USAGE;
        }
    }
    if (!a.in) {
        cli_error("fly", "no input heightfield (see tessera fly --help)");
        return CLI_USAGE;
    }
    if ((a.video || out_given) && !a.headless) {
        cli_error("fly", "%s needs --headless (the window writes no frames)", a.video ? "--video" : "--out");
        return CLI_USAGE;
    }
    if (a.headless && !frames_given)
        a.frames = 120;
    const char *names[3] = {"the input", "--stats", "--video"}, *files[3] = {a.in, a.stats, a.video};
    if (!cli_paths_distinct("fly", 3, names, files))
        return CLI_USAGE;
    const char *outputs[2] = {a.stats, a.video}; /* checked before the flight, not after it */
    /* a --stats or --video inside the frames' folder, which the flight
     * creates: checked once the input has loaded and the folder is made
     * (so a failed load leaves no folder); the others now */
    const char *early[2] = {a.stats, a.video}, *later[2] = {NULL, NULL};
    for (int i = 0; i < 2 && a.headless; i++)
        if (outputs[i] && inside_folder(outputs[i], a.out_dir))
            later[i] = outputs[i], early[i] = NULL;
    if (!cli_outputs_writable("fly", 2, early))
        return CLI_FAIL;
    tsr_heightfield *hf = cli_load_heightfield("fly", a.in, &ho);
    if (!hf)
        return CLI_FAIL;
    if ((later[0] || later[1]) && (!make_out_dir(a.out_dir) || !cli_outputs_writable("fly", 2, later))) {
        tsr_heightfield_destroy(hf);
        return CLI_FAIL;
    }
    cli_georef_warnings("fly", a.in, hf, &ho); /* warnings: also with --quiet */
    int rc = a.headless ? run_headless(&a, hf) : run_window(&a, hf);
    tsr_heightfield_destroy(hf);
    return rc;
}

const cli_command cli_cmd_fly = {"fly", "fly over a heightfield in real time (Vulkan), or render a flight", run, help};

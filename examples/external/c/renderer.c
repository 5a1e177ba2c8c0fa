/* An external renderer for tetbench in C with nothing but libc and libm (protocol version 1,
 * docs/external-renderers.md): a CPU ray caster with exact ray-cell intersection, the same
 * method as the Python example. Every tet's screen bounding box gives the pixels it may
 * cover; each pixel ray is clipped against the tet's four face planes (barycentric coordinates
 * are linear along the ray), the segment is integrated in SUBSTEPS midpoint steps, and the
 * segments are sorted per pixel and composited front to back.
 *
 * Build: cc -O2 -o renderer renderer.c -lm
 * Check: tetbench external check examples/external/c/renderer
 *
 * JSON: the protocol's requests are small, fixed objects, so a ~70-line reader that finds a
 * key in an object (skipping nested values) and reads numbers, strings and number arrays is
 * enough; a JSON library would be the only dependency. Replies are printed with printf. */
#define _GNU_SOURCE /* M_PI, clock_gettime */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define SUBSTEPS 4
#define MAX_TF 4096

/* ---- a minimal JSON reader: values are found by key inside one object, never copied ---- */
static const char *ws(const char *p) { while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++; return p; }
static const char *skip_value(const char *p);
static const char *skip_string(const char *p) { /* p at the opening quote */
    for (p++; *p && *p != '"'; p++) if (*p == '\\' && p[1]) p++;
    return *p ? p + 1 : p;
}
static const char *skip_value(const char *p) {
    p = ws(p);
    if (*p == '"') return skip_string(p);
    if (*p == '{' || *p == '[') {
        char close = *p == '{' ? '}' : ']';
        p = ws(p + 1);
        while (*p && *p != close) {
            p = skip_value(p); /* a key, or an element */
            p = ws(p);
            if (*p == ':') p = skip_value(p + 1), p = ws(p);
            if (*p == ',') p = ws(p + 1);
        }
        return *p ? p + 1 : p;
    }
    while (*p && !strchr(",}] \t\r\n", *p)) p++; /* number, true, false, null */
    return p;
}
/* The value of `key` in the object starting at `obj` ('{'), or NULL. */
static const char *find(const char *obj, const char *key) {
    if (!obj || *(obj = ws(obj)) != '{') return NULL;
    const char *p = ws(obj + 1);
    size_t n = strlen(key);
    while (*p == '"') {
        const char *k = p + 1, *end = skip_string(p);
        p = ws(end);
        if (*p != ':') return NULL;
        p = ws(p + 1);
        if ((size_t)(end - 1 - k) == n && !strncmp(k, key, n)) return p;
        p = ws(skip_value(p));
        if (*p == ',') p = ws(p + 1);
    }
    return NULL;
}
static double num(const char *v) { return v ? strtod(v, NULL) : NAN; }
static int str(const char *v, char *out, size_t cap) { /* no escapes in tetbench's paths */
    if (!v || *v != '"') return 0;
    size_t i = 0;
    for (v++; *v && *v != '"' && i + 1 < cap; v++) out[i++] = *v;
    out[i] = 0;
    return 1;
}
static int nums(const char *v, double *out, int cap) { /* numbers of a (nested) array, flat */
    int n = 0;
    const char *end = skip_value(v);
    for (const char *p = v; p < end && n < cap; p++)
        if (strchr("-0123456789", *p)) { char *e; out[n++] = strtod(p, &e); p = e - 1; }
    return n;
}

/* ---- the renderer ---- */
static float *P; static unsigned *T; static float *S;  /* mesh */
static long npoints, ntets;
static double *inv, *sv;                              /* per tet: 3x3 inverse, vertex scalars */
static double tf[MAX_TF][5]; static int ntf;          /* shared points [s, r, g, b, kappa] */
static double length_unit;
static float *image; static int W, H;
typedef struct { int pix; double t, tau, rgb[3]; } Seg;

static void *read_file(const char *path, size_t bytes) {
    FILE *f = fopen(path, "rb");
    void *b = malloc(bytes ? bytes : 1);
    if (!f || fread(b, 1, bytes, f) != bytes) { if (f) fclose(f); free(b); return NULL; }
    fclose(f);
    return b;
}
static void transfer(double s, double *rgb, double *tau) {  /* linear between shared points */
    int i = 1;
    while (i < ntf - 1 && tf[i][0] < s) i++;
    const double *a = tf[i - 1], *b = tf[ntf > 1 ? i : 0];
    double t = b[0] > a[0] ? (s - a[0]) / (b[0] - a[0]) : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    for (int c = 0; c < 3; c++) rgb[c] = a[1 + c] + t * (b[1 + c] - a[1 + c]);
    *tau = (a[4] + t * (b[4] - a[4])) / length_unit; /* kappa is per bounding-box diagonal */
}
static const char *prepare(const char *req) {
    const char *mesh = find(req, "mesh"), *raw = find(mesh, "raw"), *optics = find(req, "optics");
    char pp[4096], tp[4096], sp[4096];
    if (!str(find(raw, "points"), pp, sizeof pp) || !str(find(raw, "tets"), tp, sizeof tp) ||
        !str(find(raw, "scalars"), sp, sizeof sp)) return "prepare without raw mesh paths";
    npoints = (long)num(find(mesh, "points")); ntets = (long)num(find(mesh, "tets"));
    free(P); free(T); free(S); free(inv); free(sv);
    P = read_file(pp, npoints * 12); T = read_file(tp, ntets * 16); S = read_file(sp, npoints * 4);
    if (!P || !T || !S) return "cannot read the raw mesh files";
    double lo = num(find(optics, "scalar_min")), hi = num(find(optics, "scalar_max"));
    length_unit = num(find(optics, "length_unit"));
    static double flat[MAX_TF * 5];
    ntf = nums(find(optics, "points"), flat, MAX_TF * 5) / 5;
    if (ntf < 1) return "no transfer function points";
    memcpy(tf, flat, sizeof(double) * 5 * ntf);
    inv = malloc(sizeof(double) * 9 * ntets); sv = malloc(sizeof(double) * 4 * ntets);
    for (long t = 0; t < ntets; t++) {
        const float *v0 = P + 3 * T[4 * t];
        double e[3][3]; /* columns: v1 - v0, v2 - v0, v3 - v0 */
        for (int c = 0; c < 3; c++)
            for (int r = 0; r < 3; r++) e[r][c] = P[3 * T[4 * t + 1 + c] + r] - v0[r];
        double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                     e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                     e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
        double *m = inv + 9 * t;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) { /* adjugate / det */
                int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
                m[3 * r + c] = (e[r1][c1] * e[r2][c2] - e[r1][c2] * e[r2][c1]) / det;
            }
        for (int k = 0; k < 4; k++) {
            double s = hi > lo ? (S[T[4 * t + k]] - lo) / (hi - lo) : 0;
            sv[4 * t + k] = s < 0 ? 0 : s > 1 ? 1 : s;
        }
    }
    printf("{\"type\":\"prepared\",\"tets\":%ld,\"persistent_bytes\":%ld}\n", ntets, ntets * 104);
    return NULL;
}
static double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross(const double *a, const double *b, double *o) {
    o[0] = a[1] * b[2] - a[2] * b[1]; o[1] = a[2] * b[0] - a[0] * b[2]; o[2] = a[0] * b[1] - a[1] * b[0];
}
static void unit(double *a) { double l = sqrt(dot(a, a)); for (int i = 0; i < 3; i++) a[i] /= l; }
static int by_pixel_then_t(const void *x, const void *y) {
    const Seg *a = x, *b = y;
    if (a->pix != b->pix) return a->pix < b->pix ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}
static double now_ms(clockid_t c) { struct timespec ts; clock_gettime(c, &ts); return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6; }

static const char *render(const char *req) {
    double w0 = now_ms(CLOCK_MONOTONIC), c0 = now_ms(CLOCK_PROCESS_CPUTIME_ID);
    const char *cam = find(req, "camera");
    if (!P) return "render before prepare";
    double eye[3], target[3], up[3], f[3], r[3], u[3];
    nums(find(cam, "eye"), eye, 3); nums(find(cam, "target"), target, 3); nums(find(cam, "up"), up, 3);
    W = (int)num(find(cam, "width")); H = (int)num(find(cam, "height"));
    int persp = !strncmp(find(cam, "projection"), "\"perspective\"", 13);
    double aspect = (double)W / H;
    double half = persp ? tan(num(find(cam, "fovy_deg")) * M_PI / 360.0) : num(find(cam, "ortho_half_height"));
    for (int i = 0; i < 3; i++) f[i] = target[i] - eye[i];
    unit(f); cross(f, up, r); unit(r); cross(r, f, u);
    size_t cap = 1 << 16, n = 0;
    Seg *seg = malloc(cap * sizeof(Seg));
    for (long t = 0; t < ntets; t++) {
        double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
        int behind = 0;
        for (int k = 0; k < 4; k++) {
            const float *p = P + 3 * T[4 * t + k];
            double d[3] = {p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]};
            double z = persp ? dot(d, f) : 1.0;
            if (z <= 1e-12) { behind++; continue; }
            double px = (dot(d, r) / (z * half * aspect) + 1) * 0.5 * W;
            double py = (1 - dot(d, u) / (z * half)) * 0.5 * H;
            x0 = fmin(x0, px); x1 = fmax(x1, px); y0 = fmin(y0, py); y1 = fmax(y1, py);
        }
        if (behind == 4) continue;
        if (behind) x0 = y0 = -1e300, x1 = y1 = 1e300; /* crosses the eye plane: every pixel */
        int ax = (int)fmax(0, ceil(x0 - 0.5)), bx = (int)fmin(W - 1, floor(x1 - 0.5));
        int ay = (int)fmax(0, ceil(y0 - 0.5)), by = (int)fmin(H - 1, floor(y1 - 0.5));
        const double *m = inv + 9 * t;
        const float *v0 = P + 3 * T[4 * t];
        for (int y = ay; y <= by; y++)
            for (int x = ax; x <= bx; x++) {
                double nx = 2.0 * (x + 0.5) / W - 1, ny = 1 - 2.0 * (y + 0.5) / H, o[3], d[3];
                for (int i = 0; i < 3; i++) {
                    if (persp) { o[i] = eye[i]; d[i] = f[i] + nx * half * aspect * r[i] + ny * half * u[i]; }
                    else { o[i] = eye[i] + nx * half * aspect * r[i] + ny * half * u[i]; d[i] = f[i]; }
                }
                if (persp) unit(d);
                double rel[3] = {o[0] - v0[0], o[1] - v0[1], o[2] - v0[2]}, a[4], b[4];
                a[0] = 1; b[0] = 0;
                for (int i = 0; i < 3; i++) {
                    a[i + 1] = dot(m + 3 * i, rel); b[i + 1] = dot(m + 3 * i, d);
                    a[0] -= a[i + 1]; b[0] -= b[i + 1];
                }
                double tin = -1e300, tout = 1e300;
                int out = 0;
                for (int i = 0; i < 4; i++) {
                    if (b[i] > 0) tin = fmax(tin, -a[i] / b[i]);
                    else if (b[i] < 0) tout = fmin(tout, -a[i] / b[i]);
                    else if (a[i] < 0) out = 1;
                }
                if (out || !(tout > tin)) continue;
                double sin_ = 0, sout = 0;
                for (int i = 0; i < 4; i++) {
                    sin_ += (a[i] + tin * b[i]) * sv[4 * t + i];
                    sout += (a[i] + tout * b[i]) * sv[4 * t + i];
                }
                if (n == cap) seg = realloc(seg, (cap *= 2) * sizeof(Seg));
                Seg *g = seg + n++;
                g->pix = y * W + x; g->t = tin; g->tau = 0; g->rgb[0] = g->rgb[1] = g->rgb[2] = 0;
                double step = (tout - tin) / SUBSTEPS;
                for (int j = 0; j < SUBSTEPS; j++) {
                    double c[3], tau, s = sin_ + (j + 0.5) / SUBSTEPS * (sout - sin_);
                    transfer(s, c, &tau);
                    tau *= step;
                    double k = exp(-g->tau) * -expm1(-tau);
                    for (int i = 0; i < 3; i++) g->rgb[i] += k * c[i];
                    g->tau += tau;
                }
            }
    }
    qsort(seg, n, sizeof(Seg), by_pixel_then_t);
    free(image);
    image = calloc((size_t)W * H * 4, sizeof(float));
    double depth = 0;
    for (size_t i = 0; i < n; i++) {
        if (i == 0 || seg[i].pix != seg[i - 1].pix) depth = 0;
        float *px = image + 4 * seg[i].pix;
        double tr = exp(-depth);
        for (int c = 0; c < 3; c++) px[c] += (float)(tr * seg[i].rgb[c]);
        depth += seg[i].tau;
        px[3] = (float)-expm1(-depth);
    }
    free(seg);
    double wall = now_ms(CLOCK_MONOTONIC) - w0, cpu = fmin(now_ms(CLOCK_PROCESS_CPUTIME_ID) - c0, wall);
    printf("{\"type\":\"rendered\",\"wall_ms\":%.6f,\"cpu_ms\":%.6f,\"counters\":{\"segments\":%zu}}\n",
           wall, cpu, n);
    return NULL;
}
static const char *read_image(const char *req) {
    char path[4096];
    if (!image) return "read_image before render";
    if (!str(find(req, "path"), path, sizeof path)) return "read_image without a path";
    FILE *f = fopen(path, "wb"); /* little-endian hosts: the floats are written as they are */
    if (!f || fwrite(image, sizeof(float) * 4, (size_t)W * H, f) != (size_t)W * H) {
        if (f) fclose(f);
        return "cannot write the image";
    }
    fclose(f);
    printf("{\"type\":\"image\"}\n");
    return NULL;
}

int main(void) {
    static char line[1 << 20]; /* the longest request (prepare) is a few kB */
    unsigned one = 1;
    if (*(unsigned char *)&one != 1) { fprintf(stderr, "big-endian hosts are not supported\n"); return 1; }
    while (fgets(line, sizeof line, stdin)) {
        const char *type = find(line, "type"), *err = NULL;
        if (!type) continue;
        if (!strncmp(type, "\"hello\"", 7)) {
            const char *s = find(line, "settings");
            if (s && *ws(ws(s) + 1) != '}') err = "this renderer has no settings";
            else printf("{\"type\":\"hello\",\"protocol\":1,\"name\":\"C ray-cell caster\",\"version\":\"1\","
                        "\"settings\":{},\"capabilities\":{\"mesh_formats\":[\"raw\"]}}\n");
        } else if (!strncmp(type, "\"prepare\"", 9)) err = prepare(line);
        else if (!strncmp(type, "\"render\"", 8)) err = render(line);
        else if (!strncmp(type, "\"read_image\"", 12)) err = read_image(line);
        else if (!strncmp(type, "\"shutdown\"", 10)) { printf("{\"type\":\"bye\"}\n"); fflush(stdout); return 0; }
        else err = "unknown request type";
        if (err) printf("{\"type\":\"error\",\"message\":\"%s\"}\n", err);
        fflush(stdout);
    }
    return 0;
}

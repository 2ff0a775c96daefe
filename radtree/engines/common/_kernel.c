/* radtree.engines.common._kernel — the shadow-ray loop's per-crossing arithmetic in one pass.
 *
 * An optional accelerator of radtree/engines/numpy/shadow.py (the NumPy code there is the
 * reference and the fallback). Every number is the one the NumPy code computes: the same IEEE
 * operations in the same order on the same float64 / float32 values — compiled with
 * -ffp-contract=off -fno-fast-math (no fused multiply-add, no reassociation), no
 * transcendental functions. tests/test_numpy_kernel.py compares both paths with array_equal.
 *
 * Arrays arrive through the buffer protocol (no NumPy headers at build time); the Python side
 * (radtree/engines/common/kernel.py) checks dtypes and shapes before calling.
 *
 *   cross(tri, idx, vis, roulette, pack, sun_cos, n_tri, hour, hours, suns, eps, o, frame,
 *         o32) -> (hits, m, faint)
 *       one pass over the rays in order: for each ray i that hit (tri[i] >= 0), v =
 *       vis[idx[i]] · its triangle's specular transmittance, stored in vis; the rays with
 *       v > 0 (m of them, `faint` of them with v < roulette) are compacted in place to the
 *       front of idx, hours and o (3, n) with the next origin o + t d ± ε n past the triangle
 *       crossed (t: the plane distance towards the point sun d — suns[hours[i]], or suns[0]
 *       when hours is None and every ray has the state `hour` — summed as einsum sums three
 *       products, (a0 b0 + a2 b2) + a1 b1; ±ε on the side sun · n says, as the engine's
 *       table) and its float32 copy in trimesh's Embree frame, o32 (n, 3).
 *       pack: 8 numbers a triangle, nx ny nz v0x v0y v0z ts cos (cos = sun · n of state 0,
 *       the other states' in sun_cos[state · n_tri + triangle]): one cache line a crossing.
 *   roulette(idx, vis, hours, o, o32, m, draws, roulette) -> m'
 *       Russian roulette on the faint rays among the first m (keep = u · R < v: v = R, else
 *       0), one draw each in order; the survivors compacted in place (order kept).
 *   The two together do what the NumPy loop does per crossing (transmittance, roulette, the
 *   rays going on, their next origins): the origins of faint rays the roulette then drops
 *   are computed and discarded.
 *   distances(tri, o, d, pack, centroids, idx, t) -> hits
 *       the first hits of rays (EmbreeCaster._chunk + raycast.plane_distance): idx = tri as
 *       int64, t = the distance along d (n, 3, any strides: a broadcast row too) from o
 *       (n, 3) to the plane of the triangle hit — (v0 − o) · n / (d · n), both dot products
 *       summed as einsum sums them; |d · n| < 1e-12: (centroid − o) · d — at least 0, inf
 *       for a miss.
 *   surface(tri, t, o, d, rows, coef_t, hours, n_tri, p, nf, cosd, coef) -> None
 *       where the paths' rays hit (engine._Tracer.paths): p = o + t d, cosd = d · n (einsum's
 *       order), nf = n or −n facing the ray (n where cosd < 0), coef (4, k) = the triangle's
 *       column of coef_t (4, N) — column hours[i] · n_tri + tri[i] when hours is given.
 *   nee(nf, sd, rd, td, dnis, hours, eps, p, f, ni, so) -> m
 *       next-event estimation set-up of the path loop: cs = nf · sd (einsum's order), f =
 *       (rd cs if cs > 0 else −td cs) / π (× dnis[hours[i]] when hours is given), and for the
 *       m rays with f > 0, in order: their index ni and the shadow-ray origin
 *       so = nf · (ε sign cs) + p.
 *   frame(o, frame, o32) -> None
 *       o (3, n), any strides -> o32 (n, 3): float32(o), - origin in float64, × scale,
 *       rounded to float32 (EmbreeCaster._query's conversion).
 */
#define PY_SSIZE_T_CLEAN
#define _USE_MATH_DEFINES
#include <Python.h>
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdint.h>
#include <string.h>

/* A double rounded to float32 and back. The volatile store keeps the rounding: gcc 12 -O2's
 * SLP vectoriser folds (double)(float)x into x when it pairs two such lines (seen on x86-64). */
static inline double round32(double x) {
    volatile float f = (float)x;
    return (double)f;
}

#ifndef PREFETCH
#define PREFETCH 16
#endif
#if !defined(__GNUC__) && !defined(__clang__)
#define __builtin_prefetch(p) ((void)0)
#endif

typedef struct {
    Py_buffer view;
    int held;
} Buf;

static void release(Buf *b, int n) {
    for (int i = 0; i < n; i++)
        if (b[i].held) {
            PyBuffer_Release(&b[i].view);
            b[i].held = 0;
        }
}

/* A C-contiguous buffer of items of `itemsize` bytes, at least `need` of them. */
static int get_flat(PyObject *obj, Buf *b, int writable, Py_ssize_t itemsize,
                    Py_ssize_t need, const char *what) {
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, &b->view, flags) < 0)
        return -1;
    b->held = 1;
    if (b->view.itemsize != itemsize || b->view.len / itemsize < need) {
        PyErr_Format(PyExc_ValueError, "%s: %zd items of %zd bytes expected, got %zd of %zd",
                     what, need, itemsize, b->view.len / (b->view.itemsize ? b->view.itemsize : 1),
                     b->view.itemsize);
        return -1;
    }
    return 0;
}

/* A 2-D float64 buffer of shape (3, >= need), any strides (multiples of 8 bytes). */
static int get_rows(PyObject *obj, Buf *b, int writable, Py_ssize_t need, const char *what) {
    int flags = PyBUF_STRIDES | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, &b->view, flags) < 0)
        return -1;
    b->held = 1;
    if (b->view.ndim != 2 || b->view.itemsize != 8 || b->view.shape[0] != 3 ||
        b->view.shape[1] < need || b->view.strides[0] % 8 || b->view.strides[1] % 8 ||
        (b->view.format && strcmp(b->view.format, "d") != 0)) {
        PyErr_Format(PyExc_ValueError, "%s: a float64 array (3, >= %zd) expected", what, need);
        return -1;
    }
    return 0;
}

static PyObject *k_cross(PyObject *self, PyObject *args) {
    PyObject *otri, *oidx, *ovis, *opack, *osun_cos, *ohours, *osuns, *oo, *oframe, *oo32;
    double roulette, eps;
    Py_ssize_t n_tri, hour;
    if (!PyArg_ParseTuple(args, "OOOdOOnnOOdOOO", &otri, &oidx, &ovis, &roulette, &opack,
                          &osun_cos, &n_tri, &hour, &ohours, &osuns, &eps, &oo, &oframe, &oo32))
        return NULL;
    Buf b[10] = {{{0}}};
    if (get_flat(otri, &b[0], 0, 4, 0, "tri") < 0) goto fail;
    const Py_ssize_t n = b[0].view.len / 4;
    if (get_flat(oidx, &b[1], 1, 8, n, "idx") < 0) goto fail;
    if (get_flat(ovis, &b[2], 1, 8, 0, "vis") < 0) goto fail;
    if (get_flat(opack, &b[3], 0, 8, 8 * n_tri, "pack") < 0) goto fail;
    if (get_flat(osun_cos, &b[4], 0, 8, 0, "sun_cos") < 0) goto fail;
    const int has_hours = ohours != Py_None;
    if (has_hours && get_flat(ohours, &b[5], 1, 8, n, "hours") < 0) goto fail;
    if (get_flat(osuns, &b[6], 0, 8, 3, "suns") < 0) goto fail;
    if (get_rows(oo, &b[7], 1, n, "o") < 0) goto fail;
    if (get_flat(oframe, &b[8], 0, 8, 4, "frame") < 0) goto fail;
    if (get_flat(oo32, &b[9], 1, 4, 3 * n, "o32") < 0) goto fail;

    const int32_t *tri = b[0].view.buf;
    int64_t *idx = b[1].view.buf;
    double *vis = b[2].view.buf;
    const Py_ssize_t nvis = b[2].view.len / 8;
    const double *pack = b[3].view.buf;
    const double *sun_cos = b[4].view.buf;
    const Py_ssize_t nkeys = b[4].view.len / 8;
    int64_t *hours = has_hours ? b[5].view.buf : NULL;
    const double *suns = b[6].view.buf;
    const Py_ssize_t nsuns = b[6].view.len / 24;
    double *ox = b[7].view.buf;
    const Py_ssize_t sr = b[7].view.strides[0] / 8, sc = b[7].view.strides[1] / 8;
    double *oy = ox + sr, *oz = ox + 2 * sr;
    const double *fr = b[8].view.buf;
    const double org0 = fr[0], org1 = fr[1], org2 = fr[2], scale = fr[3];
    float *o32 = b[9].view.buf;

    Py_ssize_t hits = 0, m = 0, faint = 0;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < n; i++) {
        if (i + PREFETCH < n) { /* the triangle rows of later rays (random addresses) */
            const int32_t ta = tri[i + PREFETCH];
            if (ta >= 0 && ta < n_tri)
                __builtin_prefetch(pack + 8 * (Py_ssize_t)ta);
        }
        const int32_t t = tri[i];
        if (t < 0)
            continue;
        const int64_t j = idx[i];
        if (t >= n_tri || j < 0 || j >= nvis) {
            bad = 1;
            break;
        }
        const double *p = pack + 8 * (Py_ssize_t)t; /* nx ny nz v0x v0y v0z ts cos */
        const double v = vis[j] * p[6];
        vis[j] = v;
        hits++;
        if (!(v > 0.0))
            continue;
        faint += v < roulette;
        const int64_t h = has_hours ? hours[i] : (int64_t)hour;
        const Py_ssize_t srow = has_hours ? (Py_ssize_t)h : 0;
        double cos_sun;
        if (h == 0) {
            cos_sun = p[7];
        } else {
            const int64_t key = (int64_t)t + h * (int64_t)n_tri;
            if (key < 0 || key >= nkeys) {
                bad = 1;
                break;
            }
            cos_sun = sun_cos[key];
        }
        if (srow < 0 || srow >= nsuns) {
            bad = 1;
            break;
        }
        const double side = cos_sun < 0 ? -eps : eps;
        const double d0 = suns[3 * srow], d1 = suns[3 * srow + 1], d2 = suns[3 * srow + 2];
        const double x = ox[i * sc], y = oy[i * sc], z = oz[i * sc];
        /* (v0 - o) · n summed as einsum sums three products: (a0b0 + a2b2) + a1b1 */
        const double w0 = (p[3] - x) * p[0];
        const double w1 = (p[4] - y) * p[1];
        const double w2 = (p[5] - z) * p[2];
        double s = w0 + w2;
        s = s + w1;
        s = s / cos_sun;
        if (s < 0.0) /* np.maximum(t, 0): a NaN stays NaN */
            s = 0.0;
        /* o + t d, then + n · (±ε) */
        const double nx = (d0 * s + x) + p[0] * side;
        const double ny = (d1 * s + y) + p[1] * side;
        const double nz = (d2 * s + z) + p[2] * side;
        ox[m * sc] = nx;
        oy[m * sc] = ny;
        oz[m * sc] = nz;
        idx[m] = j;
        if (has_hours)
            hours[m] = h;
        /* float32(o), − origin in float64, × scale, rounded to float32 */
        o32[3 * m] = (float)((round32(nx) - org0) * scale);
        o32[3 * m + 1] = (float)((round32(ny) - org1) * scale);
        o32[3 * m + 2] = (float)((round32(nz) - org2) * scale);
        m++;
    }
    Py_END_ALLOW_THREADS
    release(b, 10);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "triangle, ray or hour index out of range");
        return NULL;
    }
    return Py_BuildValue("nnn", hits, m, faint);
fail:
    release(b, 10);
    return NULL;
}

static PyObject *k_roulette(PyObject *self, PyObject *args) {
    PyObject *oidx, *ovis, *ohours, *oo, *oo32, *odraws;
    Py_ssize_t m;
    double roulette;
    if (!PyArg_ParseTuple(args, "OOOOOnOd", &oidx, &ovis, &ohours, &oo, &oo32, &m, &odraws,
                          &roulette))
        return NULL;
    Buf b[6] = {{{0}}};
    if (m < 0) {
        PyErr_SetString(PyExc_ValueError, "m must be >= 0");
        return NULL;
    }
    if (get_flat(oidx, &b[0], 1, 8, m, "idx") < 0) goto fail;
    if (get_flat(ovis, &b[1], 1, 8, 0, "vis") < 0) goto fail;
    const int has_hours = ohours != Py_None;
    if (has_hours && get_flat(ohours, &b[2], 1, 8, m, "hours") < 0) goto fail;
    if (get_rows(oo, &b[3], 1, m, "o") < 0) goto fail;
    if (get_flat(oo32, &b[4], 1, 4, 3 * m, "o32") < 0) goto fail;
    if (get_flat(odraws, &b[5], 0, 8, 0, "draws") < 0) goto fail;
    int64_t *idx = b[0].view.buf;
    double *vis = b[1].view.buf;
    const Py_ssize_t nvis = b[1].view.len / 8;
    int64_t *hours = has_hours ? b[2].view.buf : NULL;
    double *ox = b[3].view.buf;
    const Py_ssize_t sr = b[3].view.strides[0] / 8, sc = b[3].view.strides[1] / 8;
    float *o32 = b[4].view.buf;
    const double *draws = b[5].view.buf;
    const Py_ssize_t ndraws = b[5].view.len / 8;
    Py_ssize_t w = 0, c = 0;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < m; i++) {
        const int64_t j = idx[i];
        if (j < 0 || j >= nvis) {
            bad = 1;
            break;
        }
        const double v = vis[j];
        if (v > 0.0 && v < roulette) {
            if (c >= ndraws) {
                bad = 2;
                break;
            }
            /* keep = u · R < v; v = where(keep, R, 0) */
            if (!(draws[c++] * roulette < v)) {
                vis[j] = 0.0;
                continue;
            }
            vis[j] = roulette;
        }
        if (w != i) {
            ox[w * sc] = ox[i * sc];
            ox[sr + w * sc] = ox[sr + i * sc];
            ox[2 * sr + w * sc] = ox[2 * sr + i * sc];
            memcpy(o32 + 3 * w, o32 + 3 * i, 3 * sizeof(float));
            idx[w] = j;
            if (has_hours)
                hours[w] = hours[i];
        }
        w++;
    }
    if (!bad && c != ndraws)
        bad = 2;
    Py_END_ALLOW_THREADS
    release(b, 6);
    if (bad == 1) {
        PyErr_SetString(PyExc_IndexError, "ray index out of range");
        return NULL;
    }
    if (bad == 2) {
        PyErr_SetString(PyExc_ValueError, "draws: one per faint shadow ray expected");
        return NULL;
    }
    return PyLong_FromSsize_t(w);
fail:
    release(b, 6);
    return NULL;
}

/* A 2-D float64 buffer of shape (n, 3), any strides (a broadcast row: stride 0). */
static int get_n3(PyObject *obj, Buf *b, Py_ssize_t n, const char *what) {
    if (PyObject_GetBuffer(obj, &b->view, PyBUF_STRIDES | PyBUF_FORMAT) < 0)
        return -1;
    b->held = 1;
    if (b->view.ndim != 2 || b->view.itemsize != 8 || b->view.shape[1] != 3 ||
        b->view.shape[0] != n || b->view.strides[0] % 8 || b->view.strides[1] % 8 ||
        (b->view.format && strcmp(b->view.format, "d") != 0)) {
        PyErr_Format(PyExc_ValueError, "%s: a float64 array (%zd, 3) expected", what, n);
        return -1;
    }
    return 0;
}

static PyObject *k_distances(PyObject *self, PyObject *args) {
    PyObject *otri, *oo, *od, *opack, *ocent, *oidx, *ot;
    if (!PyArg_ParseTuple(args, "OOOOOOO", &otri, &oo, &od, &opack, &ocent, &oidx, &ot))
        return NULL;
    Buf b[7] = {{{0}}};
    if (get_flat(otri, &b[0], 0, 4, 0, "tri") < 0) goto fail;
    const Py_ssize_t n = b[0].view.len / 4;
    if (get_n3(oo, &b[1], n, "o") < 0) goto fail;
    if (get_n3(od, &b[2], n, "d") < 0) goto fail;
    if (get_flat(opack, &b[3], 0, 8, 0, "pack") < 0) goto fail;
    if (get_flat(ocent, &b[4], 0, 8, 0, "centroids") < 0) goto fail;
    if (get_flat(oidx, &b[5], 1, 8, n, "idx") < 0) goto fail;
    if (get_flat(ot, &b[6], 1, 8, n, "t") < 0) goto fail;
    const int32_t *tri = b[0].view.buf;
    const char *obase = b[1].view.buf, *dbase = b[2].view.buf;
    const Py_ssize_t os0 = b[1].view.strides[0], os1 = b[1].view.strides[1];
    const Py_ssize_t ds0 = b[2].view.strides[0], ds1 = b[2].view.strides[1];
    const double *pack = b[3].view.buf, *cent = b[4].view.buf;
    const Py_ssize_t ntri = b[3].view.len / 64;
    int64_t *idx = b[5].view.buf;
    double *tout = b[6].view.buf;
    Py_ssize_t hits = 0;
    int bad = b[4].view.len / 24 < ntri;
    if (!bad) {
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < n; i++) {
            if (i + PREFETCH < n) {
                const int32_t ta = tri[i + PREFETCH];
                if (ta >= 0 && ta < ntri)
                    __builtin_prefetch(pack + 8 * (Py_ssize_t)ta);
            }
            const int32_t t = tri[i];
            idx[i] = t;
            if (t < 0) {
                tout[i] = Py_HUGE_VAL;
                continue;
            }
            if (t >= ntri) {
                bad = 1;
                break;
            }
            hits++;
            const double *p = pack + 8 * (Py_ssize_t)t; /* nx ny nz v0x v0y v0z - - */
            const double *oi = (const double *)(obase + i * os0);
            const double *di = (const double *)(dbase + i * ds0);
            const Py_ssize_t o1 = os1 / 8, d1s = ds1 / 8;
            const double x = oi[0], y = oi[o1], z = oi[2 * o1];
            const double dx = di[0], dy = di[d1s], dz = di[2 * d1s];
            /* einsum's order of three products: (a0b0 + a2b2) + a1b1 */
            double denom = dx * p[0] + dz * p[2];
            denom = denom + dy * p[1];
            double num = (p[3] - x) * p[0] + (p[5] - z) * p[2];
            num = num + (p[4] - y) * p[1];
            double s;
            if (fabs(denom) < 1e-12) { /* grazing: the centroid's distance along the ray */
                const double *c = cent + 3 * (Py_ssize_t)t;
                s = (c[0] - x) * dx + (c[2] - z) * dz;
                s = s + (c[1] - y) * dy;
            } else {
                s = num / denom;
            }
            if (s < 0.0) /* np.maximum(t, 0): a NaN stays NaN */
                s = 0.0;
            tout[i] = s;
        }
        Py_END_ALLOW_THREADS
    }
    release(b, 7);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "triangle index out of range");
        return NULL;
    }
    return PyLong_FromSsize_t(hits);
fail:
    release(b, 7);
    return NULL;
}

static PyObject *k_surface(PyObject *self, PyObject *args) {
    PyObject *otri, *ot, *oo, *od, *orows, *ocoef_t, *ohours, *op, *onf, *ocosd, *ocoef;
    Py_ssize_t n_tri;
    if (!PyArg_ParseTuple(args, "OOOOOOOnOOOO", &otri, &ot, &oo, &od, &orows, &ocoef_t, &ohours,
                          &n_tri, &op, &onf, &ocosd, &ocoef))
        return NULL;
    Buf b[11] = {{{0}}};
    if (get_flat(otri, &b[0], 0, 8, 0, "tri") < 0) goto fail;
    const Py_ssize_t n = b[0].view.len / 8;
    if (get_flat(ot, &b[1], 0, 8, n, "t") < 0) goto fail;
    if (get_n3(oo, &b[2], n, "o") < 0) goto fail;
    if (get_n3(od, &b[3], n, "d") < 0) goto fail;
    if (get_flat(orows, &b[4], 0, 8, 8 * n_tri, "rows") < 0) goto fail;
    if (get_flat(ocoef_t, &b[5], 0, 8, 0, "coef_t") < 0) goto fail;
    const int has_hours = ohours != Py_None;
    if (has_hours && get_flat(ohours, &b[6], 0, 8, n, "hours") < 0) goto fail;
    if (get_flat(op, &b[7], 1, 8, 3 * n, "p") < 0) goto fail;
    if (get_flat(onf, &b[8], 1, 8, 3 * n, "nf") < 0) goto fail;
    if (get_flat(ocosd, &b[9], 1, 8, n, "cosd") < 0) goto fail;
    if (get_flat(ocoef, &b[10], 1, 8, 4 * n, "coef") < 0) goto fail;
    const int64_t *tri = b[0].view.buf;
    const double *tt = b[1].view.buf;
    const char *obase = b[2].view.buf, *dbase = b[3].view.buf;
    const Py_ssize_t os0 = b[2].view.strides[0], o1 = b[2].view.strides[1] / 8;
    const Py_ssize_t ds0 = b[3].view.strides[0], d1s = b[3].view.strides[1] / 8;
    const double *rows = b[4].view.buf, *coef_t = b[5].view.buf;
    const Py_ssize_t ncols = b[5].view.len / 32;
    const int64_t *hours = has_hours ? b[6].view.buf : NULL;
    double *p = b[7].view.buf, *nf = b[8].view.buf, *cosd = b[9].view.buf,
           *coef = b[10].view.buf;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < n; i++) {
        if (i + PREFETCH < n) { /* later rays' triangle row and coefficients */
            const int64_t ta = tri[i + PREFETCH];
            const int64_t ca = has_hours ? hours[i + PREFETCH] * (int64_t)n_tri + ta : ta;
            if (ta >= 0 && ta < n_tri && ca >= 0 && ca < ncols) {
                __builtin_prefetch(rows + 8 * ta);
                for (int e = 0; e < 4; e++)
                    __builtin_prefetch(coef_t + e * ncols + ca);
            }
        }
        const int64_t t = tri[i];
        const int64_t col = has_hours ? hours[i] * (int64_t)n_tri + t : t;
        if (t < 0 || t >= n_tri || col < 0 || col >= ncols) {
            bad = 1;
            break;
        }
        const double *r = rows + 8 * t;
        const double *oi = (const double *)(obase + i * os0);
        const double *di = (const double *)(dbase + i * ds0);
        const double dx = di[0], dy = di[d1s], dz = di[2 * d1s];
        const double s = tt[i];
        p[3 * i] = s * dx + oi[0];
        p[3 * i + 1] = s * dy + oi[o1];
        p[3 * i + 2] = s * dz + oi[2 * o1];
        double c = dx * r[0] + dz * r[2]; /* einsum's order: (a0b0 + a2b2) + a1b1 */
        c = c + dy * r[1];
        cosd[i] = c;
        if (c < 0) {
            nf[3 * i] = r[0];
            nf[3 * i + 1] = r[1];
            nf[3 * i + 2] = r[2];
        } else {
            nf[3 * i] = -r[0];
            nf[3 * i + 1] = -r[1];
            nf[3 * i + 2] = -r[2];
        }
        coef[i] = coef_t[col];
        coef[n + i] = coef_t[ncols + col];
        coef[2 * n + i] = coef_t[2 * ncols + col];
        coef[3 * n + i] = coef_t[3 * ncols + col];
    }
    Py_END_ALLOW_THREADS
    release(b, 11);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "triangle or hour index out of range");
        return NULL;
    }
    Py_RETURN_NONE;
fail:
    release(b, 11);
    return NULL;
}

static PyObject *k_nee(PyObject *self, PyObject *args) {
    PyObject *onf, *osd, *ord, *otd, *odnis, *ohours, *op, *of, *oni, *oso;
    double eps;
    if (!PyArg_ParseTuple(args, "OOOOOOdOOOO", &onf, &osd, &ord, &otd, &odnis, &ohours, &eps,
                          &op, &of, &oni, &oso))
        return NULL;
    Buf b[10] = {{{0}}};
    if (get_flat(ord, &b[2], 0, 8, 0, "rd") < 0) goto fail;
    const Py_ssize_t n = b[2].view.len / 8;
    if (get_n3(onf, &b[0], n, "nf") < 0) goto fail;
    if (get_n3(osd, &b[1], n, "sd") < 0) goto fail;
    if (get_flat(otd, &b[3], 0, 8, n, "td") < 0) goto fail;
    const int has_hours = ohours != Py_None;
    if (has_hours && get_flat(odnis, &b[4], 0, 8, 1, "dnis") < 0) goto fail;
    if (has_hours && get_flat(ohours, &b[5], 0, 8, n, "hours") < 0) goto fail;
    if (get_n3(op, &b[6], n, "p") < 0) goto fail;
    if (get_flat(of, &b[7], 1, 8, n, "f") < 0) goto fail;
    if (get_flat(oni, &b[8], 1, 8, n, "ni") < 0) goto fail;
    if (get_flat(oso, &b[9], 1, 8, 3 * n, "so") < 0) goto fail;
    const char *nfb = b[0].view.buf, *sdb = b[1].view.buf, *pb = b[6].view.buf;
    const Py_ssize_t nf0 = b[0].view.strides[0], nf1 = b[0].view.strides[1] / 8;
    const Py_ssize_t sd0 = b[1].view.strides[0], sd1 = b[1].view.strides[1] / 8;
    const Py_ssize_t p0 = b[6].view.strides[0], p1 = b[6].view.strides[1] / 8;
    const double *rd = b[2].view.buf, *td = b[3].view.buf;
    const double *dnis = has_hours ? b[4].view.buf : NULL;
    const Py_ssize_t ndnis = has_hours ? b[4].view.len / 8 : 0;
    const int64_t *hours = has_hours ? b[5].view.buf : NULL;
    double *f = b[7].view.buf, *so = b[9].view.buf;
    int64_t *ni = b[8].view.buf;
    Py_ssize_t m = 0;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < n; i++) {
        const double *a = (const double *)(nfb + i * nf0);
        const double *c = (const double *)(sdb + i * sd0);
        const double ax = a[0], ay = a[nf1], az = a[2 * nf1];
        double cs = ax * c[0] + az * c[2 * sd1]; /* einsum's order: (a0b0 + a2b2) + a1b1 */
        cs = cs + ay * c[sd1];
        double fi = (cs > 0 ? rd[i] * cs : -td[i] * cs) / M_PI;
        if (has_hours) {
            const int64_t h = hours[i];
            if (h < 0 || h >= ndnis) {
                bad = 1;
                break;
            }
            fi = fi * dnis[h];
        }
        f[i] = fi;
        if (!(fi > 0))
            continue;
        /* eps · sign(cs): f > 0 needs cs != 0 */
        const double e = eps * (cs > 0 ? 1.0 : cs < 0 ? -1.0 : cs);
        const double *pi = (const double *)(pb + i * p0);
        so[3 * m] = ax * e + pi[0];
        so[3 * m + 1] = ay * e + pi[p1];
        so[3 * m + 2] = az * e + pi[2 * p1];
        ni[m++] = i;
    }
    Py_END_ALLOW_THREADS
    release(b, 10);
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "hour index out of range");
        return NULL;
    }
    return PyLong_FromSsize_t(m);
fail:
    release(b, 10);
    return NULL;
}

static PyObject *k_frame(PyObject *self, PyObject *args) {
    PyObject *oo, *oframe, *oo32;
    if (!PyArg_ParseTuple(args, "OOO", &oo, &oframe, &oo32))
        return NULL;
    Buf b[3] = {{{0}}};
    if (get_rows(oo, &b[0], 0, 0, "o") < 0) goto fail;
    const Py_ssize_t n = b[0].view.shape[1];
    if (get_flat(oframe, &b[1], 0, 8, 4, "frame") < 0) goto fail;
    if (get_flat(oo32, &b[2], 1, 4, 3 * n, "o32") < 0) goto fail;
    const char *base = b[0].view.buf;
    const Py_ssize_t sr = b[0].view.strides[0], sc = b[0].view.strides[1];
    const double *fr = b[1].view.buf;
    float *o32 = b[2].view.buf;
    Py_BEGIN_ALLOW_THREADS
    for (int a = 0; a < 3; a++) {
        const char *row = base + a * sr;
        const double org = fr[a], scale = fr[3];
        for (Py_ssize_t i = 0; i < n; i++)
            o32[3 * i + a] = (float)((round32(*(const double *)(row + i * sc)) - org) * scale);
    }
    Py_END_ALLOW_THREADS
    release(b, 3);
    Py_RETURN_NONE;
fail:
    release(b, 3);
    return NULL;
}

static PyMethodDef methods[] = {
    {"cross", k_cross, METH_VARARGS,
     "Shadow rays past the surfaces they crossed: transmittance, compaction, next origins."},
    {"roulette", k_roulette, METH_VARARGS,
     "Russian roulette on the faint shadow rays going on, survivors compacted."},
    {"distances", k_distances, METH_VARARGS,
     "First hits: triangle (int64) and float64 plane distance per ray (inf: a miss)."},
    {"surface", k_surface, METH_VARARGS,
     "Hit points, facing normals, cosines and event coefficients of the paths' rays."},
    {"nee", k_nee, METH_VARARGS,
     "Next-event estimation set-up: sun cosines, weights, shadow-ray origins."},
    {"frame", k_frame, METH_VARARGS, "Origins (3, n) float64 to Embree's float32 frame (n, 3)."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernel",
                                    "The NumPy engine's fused shadow-ray kernel (optional).", -1,
                                    methods};

PyMODINIT_FUNC PyInit__kernel(void) { return PyModule_Create(&module); }

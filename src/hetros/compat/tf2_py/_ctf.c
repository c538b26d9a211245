/*
 * hetros.compat.tf2_py._ctf: the transform tree's walk, compiled.
 *
 * walk(frames, target, source, time) does what BufferCore._lookup does for a lookup at a given time
 * (not 0) that succeeds: both walks of tf2 up the tree, each frame's transform found by bisection,
 * interpolated (translation linearly, rotation by tf2's slerp) and composed below the common ancestor,
 * with the very formulas of _core.py in the same order, so the two agree to the bit. Whatever is not
 * that plain success (a frame without data, a time outside a frame's cache, a loop, anything
 * unexpected) makes it return None: the Python walk then runs and raises tf2's error, or handles the
 * case. The Python walk stays the reference the tests hold this one against.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

#define MAX_DEPTH 1000
typedef struct { double v[7]; } Pose;

static const Pose IDENTITY = {{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0}};
static PyObject *s_static, *s_stamps, *s_entries, *s_parent, *s_pose, *s_stamp;

static void rotate(const double *q, double x, double y, double z, double *out) {
    double tx = 2.0 * (q[1] * z - q[2] * y);
    double ty = 2.0 * (q[2] * x - q[0] * z);
    double tz = 2.0 * (q[0] * y - q[1] * x);
    out[0] = x + q[3] * tx + q[1] * tz - q[2] * ty;
    out[1] = y + q[3] * ty + q[2] * tx - q[0] * tz;
    out[2] = z + q[3] * tz + q[0] * ty - q[1] * tx;
}

static Pose compose(const Pose *a, const Pose *b) {
    Pose r;
    double rv[3];
    const double *aq = a->v + 3, *bq = b->v + 3;
    rotate(aq, b->v[0], b->v[1], b->v[2], rv);
    r.v[0] = a->v[0] + rv[0];
    r.v[1] = a->v[1] + rv[1];
    r.v[2] = a->v[2] + rv[2];
    r.v[3] = aq[3] * bq[0] + aq[0] * bq[3] + aq[1] * bq[2] - aq[2] * bq[1];
    r.v[4] = aq[3] * bq[1] - aq[0] * bq[2] + aq[1] * bq[3] + aq[2] * bq[0];
    r.v[5] = aq[3] * bq[2] + aq[0] * bq[1] - aq[1] * bq[0] + aq[2] * bq[3];
    r.v[6] = aq[3] * bq[3] - aq[0] * bq[0] - aq[1] * bq[1] - aq[2] * bq[2];
    return r;
}

static Pose inverse(const Pose *a) {
    Pose r;
    double q[4] = {-a->v[3], -a->v[4], -a->v[5], a->v[6]};
    double rv[3];
    rotate(q, a->v[0], a->v[1], a->v[2], rv);
    r.v[0] = -rv[0];
    r.v[1] = -rv[1];
    r.v[2] = -rv[2];
    r.v[3] = q[0];
    r.v[4] = q[1];
    r.v[5] = q[2];
    r.v[6] = q[3];
    return r;
}

static Pose interpolate(const Pose *a, const Pose *b, double ratio) {
    Pose r;
    double ax = a->v[0], ay = a->v[1], az = a->v[2], aqx = a->v[3], aqy = a->v[4], aqz = a->v[5], aqw = a->v[6];
    double bx = b->v[0], by = b->v[1], bz = b->v[2], bqx = b->v[3], bqy = b->v[4], bqz = b->v[5], bqw = b->v[6];
    r.v[0] = ax + (bx - ax) * ratio;
    r.v[1] = ay + (by - ay) * ratio;
    r.v[2] = az + (bz - az) * ratio;
    double magnitude = sqrt((aqx * aqx + aqy * aqy + aqz * aqz + aqw * aqw) * (bqx * bqx + bqy * bqy + bqz * bqz
                                                                                + bqw * bqw));
    double product = (aqx * bqx + aqy * bqy + aqz * bqz + aqw * bqw) / magnitude;
    if (product >= 1.0 || product <= -1.0) {
        r.v[3] = aqx; r.v[4] = aqy; r.v[5] = aqz; r.v[6] = aqw;
        return r;
    }
    double sign = product < 0 ? -1.0 : 1.0;
    double theta = acos(sign * product);
    double d = 1.0 / sin(theta);
    double s0 = sin((1.0 - ratio) * theta) * d;
    double s1 = sin(sign * ratio * theta) * d;
    r.v[3] = aqx * s0 + bqx * s1;
    r.v[4] = aqy * s0 + bqy * s1;
    r.v[5] = aqz * s0 + bqz * s1;
    r.v[6] = aqw * s0 + bqw * s1;
    return r;
}

/* A stored transform's pose tuple into p; 0 on success. */
static int pose_of(PyObject *stored, Pose *p) {
    PyObject *tuple = PyObject_GetAttr(stored, s_pose);
    if (tuple == NULL) return -1;
    int bad = !PyTuple_CheckExact(tuple) || PyTuple_GET_SIZE(tuple) != 7;
    for (int i = 0; !bad && i < 7; i++) {
        PyObject *item = PyTuple_GET_ITEM(tuple, i);
        if (!PyFloat_CheckExact(item)) bad = 1;
        else p->v[i] = PyFloat_AS_DOUBLE(item);
    }
    Py_DECREF(tuple);
    return bad ? -1 : 0;
}

static int stamp_at(PyObject *stamps, Py_ssize_t i, long long *out) {
    PyObject *item = PyList_GET_ITEM(stamps, i);
    if (!PyLong_CheckExact(item)) return -1;
    int overflow = 0;
    *out = PyLong_AsLongLongAndOverflow(item, &overflow);
    return overflow ? -1 : 0;
}

/*
 * One frame's step at time: 1 with (*parent: new reference, *pose) filled; 0 where the frame has no data
 * (the top of a tree); -1 where the Python walk must decide (a time outside its data, anything odd).
 */
static int step(PyObject *frame, long long time, PyObject **parent, Pose *pose) {
    PyObject *stat = PyObject_GetAttr(frame, s_static);
    if (stat == NULL) return -1;
    if (stat != Py_None) {
        *parent = PyObject_GetAttr(stat, s_parent);
        int ok = *parent != NULL && pose_of(stat, pose) == 0;
        Py_DECREF(stat);
        if (!ok) { Py_XDECREF(*parent); return -1; }
        return 1;
    }
    Py_DECREF(stat);
    PyObject *stamps = PyObject_GetAttr(frame, s_stamps);
    PyObject *entries = PyObject_GetAttr(frame, s_entries);
    int result = -1;
    if (stamps == NULL || entries == NULL || !PyList_CheckExact(stamps) || !PyList_CheckExact(entries)) goto done;
    Py_ssize_t n = PyList_GET_SIZE(stamps);
    if (n == 0) { result = 0; goto done; }
    if (n != PyList_GET_SIZE(entries) || n == 1) goto done;  /* one entry: Python's exact-match rule */
    long long first, last;
    if (stamp_at(stamps, 0, &first) || stamp_at(stamps, n - 1, &last)) goto done;
    if (time > last || time < first) goto done;
    Py_ssize_t lo = 0, hi = n;  /* bisect_left */
    while (lo < hi) {
        Py_ssize_t mid = (lo + hi) / 2;
        long long value;
        if (stamp_at(stamps, mid, &value)) goto done;
        if (value < time) lo = mid + 1; else hi = mid;
    }
    long long after_stamp;
    if (stamp_at(stamps, lo, &after_stamp)) goto done;
    PyObject *after = PyList_GET_ITEM(entries, lo);
    if (after_stamp == time) {
        *parent = PyObject_GetAttr(after, s_parent);
        if (*parent == NULL || pose_of(after, pose)) { Py_XDECREF(*parent); goto done; }
        result = 1;
        goto done;
    }
    PyObject *before = PyList_GET_ITEM(entries, lo - 1);
    long long before_stamp;
    if (stamp_at(stamps, lo - 1, &before_stamp)) goto done;
    PyObject *before_parent = PyObject_GetAttr(before, s_parent);
    PyObject *after_parent = PyObject_GetAttr(after, s_parent);
    if (before_parent == NULL || after_parent == NULL) {
        Py_XDECREF(before_parent); Py_XDECREF(after_parent); goto done;
    }
    int same = PyObject_RichCompareBool(before_parent, after_parent, Py_EQ);
    Py_DECREF(after_parent);
    Pose a, b;
    if (same < 0 || pose_of(before, &a)) { Py_DECREF(before_parent); goto done; }
    if (same) {
        if (pose_of(after, &b)) { Py_DECREF(before_parent); goto done; }
        *pose = interpolate(&a, &b, (double)(time - before_stamp) / (double)(after_stamp - before_stamp));
    } else {
        *pose = a;
    }
    *parent = before_parent;
    result = 1;
done:
    Py_XDECREF(stamps);
    Py_XDECREF(entries);
    if (PyErr_Occurred()) PyErr_Clear();
    return result;
}

static Pose chain(const Pose *steps, Py_ssize_t n) {
    Pose pose = IDENTITY;
    for (Py_ssize_t i = 0; i < n; i++) pose = compose(&steps[i], &pose);
    return pose;
}

static PyObject *pose_tuple(const Pose *p) {
    return Py_BuildValue("(ddddddd)", p->v[0], p->v[1], p->v[2], p->v[3], p->v[4], p->v[5], p->v[6]);
}

static int same_name(PyObject *a, PyObject *b) {
    if (a == b) return 1;
    int r = PyObject_RichCompareBool(a, b, Py_EQ);
    if (r < 0) { PyErr_Clear(); return 0; }
    return r;
}

static PyObject *walk(PyObject *self, PyObject *args) {
    PyObject *frames, *target, *source;
    long long time;
    if (!PyArg_ParseTuple(args, "O!UUL", &PyDict_Type, &frames, &target, &source, &time)) return NULL;
    if (time == 0) Py_RETURN_NONE;
    Pose *up_source = NULL, *up_target = NULL;
    PyObject *on_source = PyDict_New();  /* frame name -> steps from the source */
    PyObject *result = NULL, *frame = source, *top = source;
    Py_ssize_t ns = 0, nt = 0;
    Py_INCREF(frame);
    Py_INCREF(top);
    up_source = PyMem_Malloc(sizeof(Pose) * MAX_DEPTH);
    up_target = PyMem_Malloc(sizeof(Pose) * MAX_DEPTH);
    if (on_source == NULL || up_source == NULL || up_target == NULL) goto fallback;
    int depth;
    for (depth = 0; depth < MAX_DEPTH; depth++) {
        PyObject *known = PyDict_GetItemWithError(frames, frame);  /* borrowed */
        PyObject *parent = NULL;
        Pose pose;
        int got = known == NULL ? 0 : step(known, time, &parent, &pose);
        if (got < 0) goto fallback;
        if (got == 0) { Py_SETREF(top, frame); Py_INCREF(top); break; }
        if (same_name(frame, target)) {
            Py_DECREF(parent);
            Pose r = chain(up_source, ns);
            result = pose_tuple(&r);
            goto out;
        }
        PyObject *index = PyLong_FromSsize_t(ns);
        if (index == NULL || PyDict_SetItem(on_source, frame, index) < 0) {
            Py_XDECREF(index); Py_DECREF(parent); goto fallback;
        }
        Py_DECREF(index);
        up_source[ns++] = pose;
        Py_SETREF(top, frame);
        Py_INCREF(top);
        Py_SETREF(frame, parent);
    }
    if (depth == MAX_DEPTH) goto fallback;
    /* the top is where the source's steps end */
    {
        PyObject *index = PyLong_FromSsize_t(ns);
        if (index == NULL || PyDict_SetItem(on_source, top, index) < 0) { Py_XDECREF(index); goto fallback; }
        Py_DECREF(index);
    }
    Py_SETREF(frame, target);
    Py_INCREF(frame);
    for (depth = 0; depth < MAX_DEPTH; depth++) {
        PyObject *met = PyDict_GetItemWithError(on_source, frame);  /* the first frame both walks share */
        if (met != NULL || same_name(frame, top)) {
            Py_ssize_t at = met != NULL ? PyLong_AsSsize_t(met) : ns;
            Pose inner = chain(up_target, nt), inv = inverse(&inner), outer = chain(up_source, at);
            Pose r = compose(&inv, &outer);
            result = pose_tuple(&r);
            goto out;
        }
        PyObject *known = PyDict_GetItemWithError(frames, frame);
        PyObject *parent = NULL;
        Pose pose;
        int got = known == NULL ? 0 : step(known, time, &parent, &pose);
        if (got <= 0) goto fallback;  /* a connectivity or extrapolation error: Python words it */
        if (same_name(frame, source)) {
            Py_DECREF(parent);
            Pose r = chain(up_target, nt), inv = inverse(&r);
            result = pose_tuple(&inv);
            goto out;
        }
        up_target[nt++] = pose;
        Py_SETREF(frame, parent);
    }
fallback:
    if (PyErr_Occurred()) PyErr_Clear();
    result = Py_None;
    Py_INCREF(result);
out:
    Py_XDECREF(frame);
    Py_XDECREF(top);
    Py_XDECREF(on_source);
    PyMem_Free(up_source);
    PyMem_Free(up_target);
    return result;
}

static PyMethodDef methods[] = {
    {"walk", walk, METH_VARARGS, "walk(frames, target, source, time) -> pose tuple, or None: let Python decide"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_ctf", NULL, -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__ctf(void) {
    s_static = PyUnicode_InternFromString("static");
    s_stamps = PyUnicode_InternFromString("stamps");
    s_entries = PyUnicode_InternFromString("entries");
    s_parent = PyUnicode_InternFromString("parent");
    s_pose = PyUnicode_InternFromString("pose");
    s_stamp = PyUnicode_InternFromString("stamp");
    if (!s_static || !s_stamps || !s_entries || !s_parent || !s_pose || !s_stamp) return NULL;
    return PyModule_Create(&module);
}

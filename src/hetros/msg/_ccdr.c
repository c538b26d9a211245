/*
 * hetros.msg._ccdr: the compiled CDR / ROS 1 codec, one interpreter for every message type.
 *
 * Python compiles each type into a program (hetros/msg/_compiled.py): one op per field,
 * with the slot offset of the field in the message object, the primitive kind, the fixed
 * length or bound, the nested type's program. This file walks such programs to size,
 * encode and decode messages, reading and writing the objects' slots directly.
 *
 * It never reports an error of its own about a message or bytes. Whatever it does not
 * accept (a value of an unexpected type, an out-of-range integer, bytes that do not fit,
 * a bound exceeded, invalid UTF-8) makes it call the generated Python function it stands
 * in for, with the same arguments: that function raises exactly the error users see
 * without the extension (field path and offset included), or handles the case. So the
 * two paths cannot disagree on what is an error, and the Python one stays the reference
 * that tests cross-check this one against.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

enum { OP_PRIM, OP_STRING, OP_NESTED, OP_PRIM_ARRAY, OP_PRIM_SEQ, OP_STR_ARRAY, OP_STR_SEQ, OP_MSG_ARRAY,
       OP_MSG_SEQ };
enum { P_BOOL, P_U8, P_I8, P_I16, P_U16, P_I32, P_U32, P_I64, P_U64, P_F32, P_F64, P_COUNT };
static const int prim_size[P_COUNT] = {1, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};

struct Type;

typedef struct {
    int kind;
    int prim;
    Py_ssize_t offset;   /* slot offset of the field in the message object */
    Py_ssize_t length;   /* fixed length of an array, bound of a sequence (0: none) */
    struct Type *sub;    /* nested message type */
    PyObject *dtype;     /* numpy dtype of a primitive array (owned) */
    PyObject *name;      /* the field's attribute name (owned) */
} Op;

typedef struct Type {
    PyTypeObject *cls;    /* owned */
    PyTypeObject *frozen; /* owned */
    Py_ssize_t loan_offset;
    int bounded_strings; /* a bounded string anywhere in it: validation is the generated code's */
    Py_ssize_t nops;
    Op *ops;
} Type;

/* Raised inside this file only: "hand this call to the Python function". */
#define REFUSE (-2)

typedef struct {
    char *data;
    Py_ssize_t len;
    int ros1;
} Out;

typedef struct {
    const char *data;
    Py_ssize_t end;
    int ros1;
    PyObject *buffer; /* what numpy views are made on */
    PyObject *frombuffer;
    PyObject *frozenlist;
} In;

/* ---------------------------------------------------------------------------------------- */
/* programs                                                                                   */

static void type_free(Type *type)
{
    if (type == NULL)
        return;
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        Py_XDECREF(type->ops[i].dtype);
        Py_XDECREF(type->ops[i].name);
        type_free(type->ops[i].sub);
    }
    PyMem_Free(type->ops);
    Py_XDECREF(type->cls);
    Py_XDECREF(type->frozen);
    PyMem_Free(type);
}

static int slot_offset(PyObject *descr, Py_ssize_t *offset)
{
    if (!Py_IS_TYPE(descr, &PyMemberDescr_Type)) {
        PyErr_Format(PyExc_TypeError, "a field must be a slot (member descriptor), not %R", descr);
        return -1;
    }
    PyMemberDef *member = ((PyMemberDescrObject *)descr)->d_member;
    if (member->type != T_OBJECT_EX) {
        PyErr_Format(PyExc_TypeError, "slot %s must hold an object", member->name);
        return -1;
    }
    *offset = member->offset;
    return 0;
}

/* spec: (cls, frozen, loan_descriptor, bounded_strings, ((kind, descriptor, prim, length, sub_spec, dtype), ...)) */
static Type *type_from_spec(PyObject *spec)
{
    PyObject *cls, *frozen, *loan, *ops;
    int bounded_strings;
    if (!PyArg_ParseTuple(spec, "O!O!OpO!", &PyType_Type, &cls, &PyType_Type, &frozen, &loan, &bounded_strings,
                          &PyTuple_Type, &ops))
        return NULL;
    if (!PyType_IsSubtype((PyTypeObject *)frozen, (PyTypeObject *)cls)) {
        PyErr_SetString(PyExc_TypeError, "the frozen class must derive from the message class");
        return NULL;
    }
    Type *type = PyMem_Calloc(1, sizeof(Type));
    if (type == NULL)
        return (Type *)PyErr_NoMemory();
    type->cls = (PyTypeObject *)Py_NewRef(cls);
    type->frozen = (PyTypeObject *)Py_NewRef(frozen);
    type->bounded_strings = bounded_strings;
    type->nops = PyTuple_GET_SIZE(ops);
    type->ops = PyMem_Calloc(type->nops ? type->nops : 1, sizeof(Op));
    if (type->ops == NULL) {
        type->nops = 0;
        type_free(type);
        return (Type *)PyErr_NoMemory();
    }
    if (slot_offset(loan, &type->loan_offset) < 0)
        goto fail;
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        Op *op = &type->ops[i];
        PyObject *descr, *sub, *dtype;
        if (!PyArg_ParseTuple(PyTuple_GET_ITEM(ops, i), "iOinOO", &op->kind, &descr, &op->prim, &op->length, &sub,
                              &dtype))
            goto fail;
        if (op->kind < OP_PRIM || op->kind > OP_MSG_SEQ || op->prim < 0 || op->prim >= P_COUNT) {
            PyErr_Format(PyExc_ValueError, "op %zd: unknown kind %d or primitive %d", i, op->kind, op->prim);
            goto fail;
        }
        if (slot_offset(descr, &op->offset) < 0)
            goto fail;
        op->name = Py_NewRef(PyDescr_NAME(descr));
        if (sub != Py_None && (op->sub = type_from_spec(sub)) == NULL)
            goto fail;
        if ((op->kind == OP_NESTED || op->kind == OP_MSG_ARRAY || op->kind == OP_MSG_SEQ) && op->sub == NULL) {
            PyErr_Format(PyExc_ValueError, "op %zd: a message field needs its type's program", i);
            goto fail;
        }
        if (dtype != Py_None)
            op->dtype = Py_NewRef(dtype);
        if ((op->kind == OP_PRIM_ARRAY || op->kind == OP_PRIM_SEQ) && op->dtype == NULL) {
            PyErr_Format(PyExc_ValueError, "op %zd: a primitive array needs its dtype", i);
            goto fail;
        }
    }
    return type;
fail:
    type_free(type);
    return NULL;
}

#define SLOT(obj, offset) (*(PyObject **)((char *)(obj) + (offset)))

/* the message's own type or its frozen twin, or a subclass of either that adds no storage (the
   rclpy flavour's classes: properties over the same slots): only then are the slot offsets the
   program's */
static inline int is_type(PyObject *obj, const Type *type)
{
    PyTypeObject *actual = Py_TYPE(obj);
    if (actual == type->cls || actual == type->frozen)
        return 1;
    return actual->tp_basicsize == type->cls->tp_basicsize && actual->tp_dictoffset == 0 &&
           (PyType_IsSubtype(actual, type->cls) || PyType_IsSubtype(actual, type->frozen));
}

static inline Py_ssize_t align(Py_ssize_t pos, int size, int ros1)
{
    return ros1 ? pos : (pos + size - 1) & -(Py_ssize_t)size;
}

/* ---------------------------------------------------------------------------------------- */
/* size and encode: one walk; with out->data NULL it only counts                             */

static inline int put_align(Out *out, Py_ssize_t *pos, int size)
{
    Py_ssize_t aligned = align(*pos, size, out->ros1);
    if (out->data != NULL && aligned != *pos) {
        if (aligned > out->len)
            return REFUSE;
        memset(out->data + *pos, 0, aligned - *pos);
    }
    *pos = aligned;
    return 0;
}

static inline int put_u32(Out *out, Py_ssize_t *pos, uint32_t value)
{
    if (put_align(out, pos, 4) < 0)
        return REFUSE;
    if (out->data != NULL) {
        if (*pos + 4 > out->len)
            return REFUSE;
        memcpy(out->data + *pos, &value, 4);
    }
    *pos += 4;
    return 0;
}

/* the integer kinds' ranges, by primitive code (P_U64 is read unsigned) */
static const long long int_min[P_COUNT] = {0, 0, INT8_MIN, INT16_MIN, 0, INT32_MIN, 0, LLONG_MIN, 0, 0, 0};
static const long long int_max[P_COUNT] = {0, UINT8_MAX, INT8_MAX, INT16_MAX, UINT16_MAX, INT32_MAX, UINT32_MAX,
                                           LLONG_MAX, 0, 0, 0};

/* an int of the primitive's range, as its two's complement bits; REFUSE when it is not */
static int as_int(PyObject *value, int prim, unsigned long long *bits)
{
    if (prim == P_U64) {
        *bits = PyLong_AsUnsignedLongLong(value);
        return *bits == (unsigned long long)-1 && PyErr_Occurred() ? REFUSE : 0;
    }
    int overflow = 0;
    long long number = PyLong_AsLongLongAndOverflow(value, &overflow);
    if (overflow || (number == -1 && PyErr_Occurred()) || number < int_min[prim] || number > int_max[prim])
        return REFUSE;
    *bits = (unsigned long long)number;
    return 0;
}

static int put_prim(Out *out, Py_ssize_t *pos, int prim, PyObject *value)
{
    int size = prim_size[prim];
    if (put_align(out, pos, size) < 0)
        return REFUSE;
    if (out->data == NULL) {
        *pos += size;
        return 0;
    }
    if (*pos + size > out->len)
        return REFUSE;
    char *at = out->data + *pos;
    *pos += size;
    if (prim == P_BOOL) {
        int truth = PyObject_IsTrue(value);
        if (truth < 0)
            return REFUSE;
        *at = (char)truth;
        return 0;
    }
    if (prim == P_F32 || prim == P_F64) {
        if (!PyFloat_Check(value) && !PyLong_Check(value))
            return REFUSE; /* struct takes __float__ objects too: the Python path decides */
        double number = PyFloat_AsDouble(value);
        if (number == -1.0 && PyErr_Occurred())
            return REFUSE;
        if (prim == P_F64) {
            memcpy(at, &number, 8);
            return 0;
        }
        float narrow = (float)number;
        if (isinf(narrow) && !isinf(number))
            return REFUSE;
        memcpy(at, &narrow, 4);
        return 0;
    }
    if (!PyLong_Check(value))
        return REFUSE; /* numpy integers and other __index__ objects: the Python path */
    unsigned long long bits;
    if (as_int(value, prim, &bits) < 0)
        return REFUSE;
    memcpy(at, &bits, size); /* the low bytes: the host is little-endian (the codecs are built only there) */
    return 0;
}

static int put_string(Out *out, Py_ssize_t *pos, PyObject *value)
{
    if (!PyUnicode_Check(value))
        return REFUSE;
    Py_ssize_t length;
    const char *text = PyUnicode_AsUTF8AndSize(value, &length);
    if (text == NULL)
        return REFUSE;
    int nul = out->ros1 ? 0 : 1;
    if (length + nul > UINT32_MAX)
        return REFUSE;
    if (put_u32(out, pos, (uint32_t)(length + nul)) < 0)
        return REFUSE;
    if (out->data != NULL) {
        if (*pos + length + nul > out->len)
            return REFUSE;
        memcpy(out->data + *pos, text, length);
        if (nul)
            out->data[*pos + length] = 0;
    }
    *pos += length + nul;
    return 0;
}

/* a primitive array: C-contiguous, exactly count elements of the field's size */
static int put_block(Out *out, Py_ssize_t *pos, int prim, PyObject *value, Py_ssize_t count, int sequence)
{
    int size = prim_size[prim];
    if (!sequence || count)
        if (put_align(out, pos, size) < 0)
            return REFUSE;
    Py_ssize_t nbytes = count * size;
    if (out->data == NULL) {
        *pos += nbytes;
        return 0;
    }
    if (*pos + nbytes > out->len)
        return REFUSE;
    Py_buffer view;
    if (PyObject_GetBuffer(value, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return REFUSE;
    int ok = view.len == nbytes;
    /* a byte field takes its buffer as it is: only a byte format fits (as memoryview assignment) */
    if (ok && prim == P_U8 && view.format != NULL && strcmp(view.format, "B") != 0 && strcmp(view.format, "<B") != 0
        && strcmp(view.format, "=B") != 0)
        ok = 0;
    if (ok)
        memcpy(out->data + *pos, view.buf, nbytes);
    PyBuffer_Release(&view);
    if (!ok)
        return REFUSE;
    *pos += nbytes;
    return 0;
}

static int put_message(Out *out, Py_ssize_t *pos, const Type *type, PyObject *message, int lean);

static int put_items(Out *out, Py_ssize_t *pos, const Op *op, PyObject *value, int sequence)
{
    if (!PyList_Check(value) && !PyTuple_Check(value))
        return REFUSE;
    Py_ssize_t count = PySequence_Fast_GET_SIZE(value);
    if (sequence) {
        if (count > UINT32_MAX || put_u32(out, pos, (uint32_t)count) < 0)
            return REFUSE;
    }
    for (Py_ssize_t i = 0; i < PySequence_Fast_GET_SIZE(value); i++) {
        PyObject *item = PySequence_Fast_GET_ITEM(value, i);
        int status = op->sub != NULL ? put_message(out, pos, op->sub, item, 0) : put_string(out, pos, item);
        if (status < 0)
            return REFUSE;
    }
    return 0;
}

static int put_message(Out *out, Py_ssize_t *pos, const Type *type, PyObject *message, int lean)
{
    if (!is_type(message, type))
        return REFUSE;
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        const Op *op = &type->ops[i];
        PyObject *value = SLOT(message, op->offset);
        if (value == NULL)
            return REFUSE;
        int status = 0;
        switch (op->kind) {
        case OP_PRIM:
            status = put_prim(out, pos, op->prim, value);
            break;
        case OP_STRING:
            status = put_string(out, pos, value);
            break;
        case OP_NESTED:
            status = put_message(out, pos, op->sub, value, lean);
            break;
        case OP_PRIM_ARRAY:
            status = put_block(out, pos, op->prim, value, op->length, 0);
            break;
        case OP_PRIM_SEQ: {
            if (lean) { /* the array travels beside the body */
                status = put_u32(out, pos, 0);
                break;
            }
            Py_ssize_t count = PyObject_Size(value);
            if (count < 0 || count > UINT32_MAX || put_u32(out, pos, (uint32_t)count) < 0)
                return REFUSE;
            status = put_block(out, pos, op->prim, value, count, 1);
            break;
        }
        case OP_STR_ARRAY:
        case OP_MSG_ARRAY:
            status = put_items(out, pos, op, value, 0);
            break;
        default: /* OP_STR_SEQ, OP_MSG_SEQ */
            status = put_items(out, pos, op, value, 1);
            break;
        }
        if (status < 0)
            return REFUSE;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* decode                                                                                     */

static inline int need(const In *in, Py_ssize_t pos, Py_ssize_t count)
{
    return count >= 0 && pos <= in->end && count <= in->end - pos;
}

static int get_u32(const In *in, Py_ssize_t *pos, uint32_t *value)
{
    *pos = align(*pos, 4, in->ros1);
    if (!need(in, *pos, 4))
        return REFUSE;
    memcpy(value, in->data + *pos, 4);
    *pos += 4;
    return 0;
}

static PyObject *get_prim(const In *in, Py_ssize_t *pos, int prim)
{
    int size = prim_size[prim];
    *pos = align(*pos, size, in->ros1);
    if (!need(in, *pos, size))
        return NULL;
    const char *at = in->data + *pos;
    *pos += size;
    switch (prim) {
    case P_BOOL: return PyBool_FromLong(*at != 0);
    case P_U8: return PyLong_FromLong(*(const uint8_t *)at);
    case P_I8: return PyLong_FromLong(*(const int8_t *)at);
    case P_I16: { int16_t v; memcpy(&v, at, 2); return PyLong_FromLong(v); }
    case P_U16: { uint16_t v; memcpy(&v, at, 2); return PyLong_FromLong(v); }
    case P_I32: { int32_t v; memcpy(&v, at, 4); return PyLong_FromLong(v); }
    case P_U32: { uint32_t v; memcpy(&v, at, 4); return PyLong_FromUnsignedLong(v); }
    case P_I64: { int64_t v; memcpy(&v, at, 8); return PyLong_FromLongLong(v); }
    case P_U64: { uint64_t v; memcpy(&v, at, 8); return PyLong_FromUnsignedLongLong(v); }
    case P_F32: { float v; memcpy(&v, at, 4); return PyFloat_FromDouble(v); }
    default: { double v; memcpy(&v, at, 8); return PyFloat_FromDouble(v); }
    }
}

static PyObject *get_string(const In *in, Py_ssize_t *pos)
{
    uint32_t length;
    if (get_u32(in, pos, &length) < 0 || !need(in, *pos, length))
        return NULL;
    Py_ssize_t text = length;
    if (!in->ros1) {
        if (length < 1 || in->data[*pos + length - 1] != 0)
            return NULL;
        text -= 1;
    }
    PyObject *value = PyUnicode_DecodeUTF8(in->data + *pos, text, "strict");
    *pos += length;
    return value;
}

static PyObject *get_block(const In *in, Py_ssize_t *pos, const Op *op, Py_ssize_t count)
{
    int size = prim_size[op->prim];
    if (op->kind == OP_PRIM_ARRAY || count)
        *pos = align(*pos, size, in->ros1);
    if (!need(in, *pos, count * size))
        return NULL;
    PyObject *args[4] = {in->buffer, op->dtype, NULL, NULL};
    PyObject *result = NULL;
    args[2] = PyLong_FromSsize_t(count);
    args[3] = PyLong_FromSsize_t(*pos);
    if (args[2] != NULL && args[3] != NULL)
        result = PyObject_Vectorcall(in->frombuffer, args, 4, NULL);
    Py_XDECREF(args[2]);
    Py_XDECREF(args[3]);
    *pos += count * size;
    return result;
}

static PyObject *get_message(const In *in, Py_ssize_t *pos, const Type *type);

static PyObject *get_items(const In *in, Py_ssize_t *pos, const Op *op, Py_ssize_t count)
{
    /* every string and (but ROS 1's empty messages) every message takes at least a byte: a
       count beyond the bytes left is refused before anything is allocated for it (a forged
       4-byte count made a list of 4 billion slots); the Python path decides the rare rest */
    if (count > in->end - *pos)
        return NULL;
    PyObject *items = PyList_New(count);
    if (items == NULL)
        return NULL;
    for (Py_ssize_t i = 0; i < count; i++) {
        PyObject *item = op->sub != NULL ? get_message(in, pos, op->sub) : get_string(in, pos);
        if (item == NULL) {
            Py_DECREF(items);
            return NULL;
        }
        PyList_SET_ITEM(items, i, item);
    }
    PyObject *frozen = PyObject_CallOneArg(in->frozenlist, items);
    Py_DECREF(items);
    return frozen;
}

static PyObject *get_message(const In *in, Py_ssize_t *pos, const Type *type)
{
    /* made as the frozen twin at once: the Python path makes the thawed class and swaps */
    PyObject *message = type->frozen->tp_alloc(type->frozen, 0);
    if (message == NULL)
        return NULL;
    SLOT(message, type->loan_offset) = Py_NewRef(Py_None);
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        const Op *op = &type->ops[i];
        PyObject *value = NULL;
        uint32_t count;
        switch (op->kind) {
        case OP_PRIM:
            value = get_prim(in, pos, op->prim);
            break;
        case OP_STRING:
            value = get_string(in, pos);
            break;
        case OP_NESTED:
            value = get_message(in, pos, op->sub);
            break;
        case OP_PRIM_ARRAY:
            value = get_block(in, pos, op, op->length);
            break;
        case OP_PRIM_SEQ:
            if (get_u32(in, pos, &count) == 0 && (!op->length || count <= op->length))
                value = get_block(in, pos, op, count);
            break;
        case OP_STR_ARRAY:
        case OP_MSG_ARRAY:
            value = get_items(in, pos, op, op->length);
            break;
        default: /* OP_STR_SEQ, OP_MSG_SEQ */
            if (get_u32(in, pos, &count) == 0 && (!op->length || count <= op->length))
                value = get_items(in, pos, op, count);
            break;
        }
        if (value == NULL) {
            Py_DECREF(message);
            return NULL;
        }
        PyObject *old = SLOT(message, op->offset);
        SLOT(message, op->offset) = value;
        Py_XDECREF(old);
    }
    return message;
}


/* ---------------------------------------------------------------------------------------- */
/* validate: accepts what the generated validator accepts without a word or a change        */

static PyTypeObject *ndarray_type; /* set at module init from numpy, borrowed through the module */
static PyObject *str_dtype, *str_size;

/* The head of numpy's array object (PyArrayObject_fields), laid out alike from numpy 1.7
   through 2.x. It is read only once configure() has checked it against real arrays; until
   then, or if anything differs, arrays are read through their Python attributes. Reading
   the head is what makes sealing a loaned array cheap: ``arr.flags.writeable = False``
   through attributes costs 0.25 us, a third of a small hop's sealing. */
typedef struct {
    PyObject_HEAD
    char *data;
    int nd;
    Py_ssize_t *dimensions;
    Py_ssize_t *strides;
    PyObject *base;
    PyObject *descr;
    int flags;
} ArrayHead;
#define ARRAY_WRITEABLE 0x0400          /* NPY_ARRAY_WRITEABLE */
#define ARRAY_WARN_ON_WRITE 0x80000000u /* NPY_ARRAY_WARN_ON_WRITE */
#define HEAD(array) ((ArrayHead *)(array))
static int array_head_checked;

/* a one-dimensional array's element count; -1 (no error set) when only attributes can tell */
static Py_ssize_t array_size_1d(PyObject *array)
{
    return array_head_checked && HEAD(array)->nd == 1 ? HEAD(array)->dimensions[0] : -1;
}

static int check_int(PyObject *value, int prim)
{
    unsigned long long bits;
    return PyLong_CheckExact(value) ? as_int(value, prim, &bits) : REFUSE;
}

static int check_prim(PyObject *value, int prim)
{
    if (prim == P_BOOL)
        return Py_IS_TYPE(value, &PyBool_Type) ? 0 : REFUSE;
    if (prim == P_F64)
        return PyFloat_CheckExact(value) ? 0 : REFUSE;
    if (prim == P_F32) {
        if (!PyFloat_CheckExact(value))
            return REFUSE;
        double number = PyFloat_AS_DOUBLE(value);
        return isfinite(number) && fabs(number) > FLT_MAX ? REFUSE : 0;
    }
    return check_int(value, prim);
}

static int check_array(PyObject *value, const Op *op)
{
    if (ndarray_type == NULL || !Py_IS_TYPE(value, ndarray_type))
        return REFUSE;
    if (array_head_checked) {
        if (HEAD(value)->descr != op->dtype)
            return REFUSE; /* an equal but distinct dtype: the generated validator decides */
    } else {
        PyObject *dtype = PyObject_GetAttr(value, str_dtype);
        if (dtype == NULL)
            return REFUSE;
        int same = dtype == op->dtype;
        Py_DECREF(dtype);
        if (!same)
            return REFUSE;
    }
    if (op->length) {
        Py_ssize_t count = array_size_1d(value);
        if (count < 0) {
            PyObject *size = PyObject_GetAttr(value, str_size);
            if (size == NULL)
                return REFUSE;
            count = PyLong_AsSsize_t(size);
            Py_DECREF(size);
        }
        if (count < 0 || (op->kind == OP_PRIM_ARRAY ? count != op->length : count > op->length))
            return REFUSE;
    }
    return 0;
}

static int check_message(PyObject *message, const Type *type)
{
    if (!is_type(message, type) || type->bounded_strings)
        return REFUSE;
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        const Op *op = &type->ops[i];
        PyObject *value = SLOT(message, op->offset);
        if (value == NULL)
            return REFUSE;
        int status = 0;
        switch (op->kind) {
        case OP_PRIM:
            status = check_prim(value, op->prim);
            break;
        case OP_STRING:
            status = PyUnicode_CheckExact(value) ? 0 : REFUSE;
            break;
        case OP_NESTED:
            status = check_message(value, op->sub);
            break;
        case OP_PRIM_ARRAY:
        case OP_PRIM_SEQ:
            status = check_array(value, op);
            break;
        default: { /* lists of strings or messages */
            if (!PyList_Check(value) && !PyTuple_Check(value))
                return REFUSE;
            Py_ssize_t count = PySequence_Fast_GET_SIZE(value);
            int fixed = op->kind == OP_STR_ARRAY || op->kind == OP_MSG_ARRAY;
            if (op->length && (fixed ? count != op->length : count > op->length))
                return REFUSE;
            for (Py_ssize_t k = 0; k < count && status == 0; k++) {
                PyObject *item = PySequence_Fast_GET_ITEM(value, k);
                status = op->sub != NULL ? check_message(item, op->sub) : (PyUnicode_CheckExact(item) ? 0 : REFUSE);
            }
        }
        }
        if (status < 0)
            return REFUSE;
    }
    return 0;
}


/* ---------------------------------------------------------------------------------------- */
/* seal: what the generated sealer does, for messages of the type's own classes             */

enum { SEAL_FREEZE, SEAL_COPY, SEAL_KEEP }; /* _message.py's _FREEZE, _COPY, _KEEP */

static PyTypeObject *loan_buffer_type; /* hetros.msg._message.LoanBuffer */
static PyObject *seal_array_function;  /* hetros.msg._message._seal_array */
static PyObject *frozenlist_type;      /* hetros.msg._message.FrozenList */
static PyObject *str_base, *str_flags, *str_writeable, *str_hetros_seal;

/* hetros' own memory: an array (or views of one) on a LoanBuffer, directly or through a memoryview; -1 on error */
static int is_loaned(PyObject *array)
{
    if (array_head_checked) {
        PyObject *base = HEAD(array)->base;
        while (base != NULL && Py_IS_TYPE(base, ndarray_type))
            base = HEAD(base)->base;
        return base != NULL && (Py_IS_TYPE(base, loan_buffer_type)
                                || (PyMemoryView_Check(base) && PyMemoryView_GET_BASE(base) != NULL
                                    && Py_IS_TYPE(PyMemoryView_GET_BASE(base), loan_buffer_type)));
    }
    PyObject *base = PyObject_GetAttr(array, str_base);
    while (base != NULL && Py_IS_TYPE(base, ndarray_type)) {
        PyObject *next = PyObject_GetAttr(base, str_base);
        Py_DECREF(base);
        base = next;
    }
    if (base == NULL)
        return -1;
    int loaned = Py_IS_TYPE(base, loan_buffer_type)
                 || (PyMemoryView_Check(base) && PyMemoryView_GET_BASE(base) != NULL
                     && Py_IS_TYPE(PyMemoryView_GET_BASE(base), loan_buffer_type));
    Py_DECREF(base);
    return loaned;
}

static int make_read_only(PyObject *array)
{
    if (array_head_checked) { /* what numpy's own setter does for False: clear both flags */
        HEAD(array)->flags = (int)((unsigned)HEAD(array)->flags & ~(ARRAY_WRITEABLE | ARRAY_WARN_ON_WRITE));
        return 0;
    }
    PyObject *flags = PyObject_GetAttr(array, str_flags);
    if (flags == NULL)
        return -1;
    int status = PyObject_SetAttr(flags, str_writeable, Py_False);
    Py_DECREF(flags);
    return status;
}

static int seal_python(PyObject *message, PyObject *callers)
{
    PyObject *sealer = PyObject_GetAttr((PyObject *)Py_TYPE(message), str_hetros_seal);
    if (sealer == NULL)
        return -1;
    PyObject *result = PyObject_CallFunctionObjArgs(sealer, message, callers, NULL);
    Py_DECREF(sealer);
    Py_XDECREF(result);
    return result == NULL ? -1 : 0;
}

static int seal_message(PyObject *message, const Type *type, int callers, PyObject *callers_object);

/* one array field: loaned arrays become read-only in every mode; under KEEP the caller's own
   arrays are left alone (the transport copies them); the rest is _seal_array's */
static int seal_array(PyObject *holder, PyObject *name, PyObject *array, int callers, PyObject *callers_object)
{
    if (!Py_IS_TYPE(array, ndarray_type))
        return 0;
    int loaned = is_loaned(array);
    if (loaned < 0)
        return -1;
    if (loaned)
        return make_read_only(array);
    if (callers == SEAL_KEEP)
        return 0;
    PyObject *result = PyObject_CallFunctionObjArgs(seal_array_function, holder, name, array, callers_object, NULL);
    Py_XDECREF(result);
    return result == NULL ? -1 : 0;
}

static int seal_nested(PyObject *value, const Type *sub, int callers, PyObject *callers_object)
{
    if (Py_IS_TYPE(value, sub->frozen))
        return 0;
    if (Py_IS_TYPE(value, sub->cls))
        return seal_message(value, sub, callers, callers_object);
    return seal_python(value, callers_object);
}

/* in field order; list fields become FrozenLists and the class its frozen twin last */
static int seal_message(PyObject *message, const Type *type, int callers, PyObject *callers_object)
{
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        const Op *op = &type->ops[i];
        PyObject *value = SLOT(message, op->offset);
        if (value == NULL) {
            PyErr_Format(PyExc_AttributeError, "a %s has no field %R", type->cls->tp_name, op->name);
            return -1;
        }
        int status = 0;
        switch (op->kind) {
        case OP_PRIM_ARRAY:
        case OP_PRIM_SEQ:
            status = seal_array(message, op->name, value, callers, callers_object);
            break;
        case OP_NESTED:
            status = seal_nested(value, op->sub, callers, callers_object);
            break;
        case OP_MSG_ARRAY:
        case OP_MSG_SEQ: {
            PyObject *items = PySequence_Fast(value, "a list of messages");
            if (items == NULL)
                return -1;
            for (Py_ssize_t k = 0; k < PySequence_Fast_GET_SIZE(items) && status == 0; k++)
                status = seal_nested(PySequence_Fast_GET_ITEM(items, k), op->sub, callers, callers_object);
            Py_DECREF(items);
            break;
        }
        default:
            break;
        }
        if (status < 0)
            return -1;
    }
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        const Op *op = &type->ops[i];
        if (op->kind != OP_STR_ARRAY && op->kind != OP_STR_SEQ && op->kind != OP_MSG_ARRAY && op->kind != OP_MSG_SEQ)
            continue;
        PyObject *value = SLOT(message, op->offset);
        if ((PyObject *)Py_TYPE(value) == frozenlist_type)
            continue;
        PyObject *frozen = PyObject_CallOneArg(frozenlist_type, value);
        if (frozen == NULL)
            return -1;
        SLOT(message, op->offset) = frozen;
        Py_DECREF(value);
    }
    Py_INCREF(type->frozen); /* as object.__setattr__(message, "__class__", frozen) does for heap types */
    Py_SET_TYPE(message, type->frozen);
    Py_DECREF(type->cls);
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* copy: what _message.copy does, for messages whose every value is as validation accepts   */

static PyObject *str_copy;

static PyObject *copy_message(PyObject *message, const Type *type);

/* a writable list of copies of ``items`` (strings shared, messages copied); NULL with no
   error set when an item is not what the field holds */
static PyObject *copy_items(PyObject *items, const Op *op)
{
    if (!PyList_Check(items))
        return NULL;
    Py_ssize_t count = PyList_GET_SIZE(items);
    int fixed = op->kind == OP_STR_ARRAY || op->kind == OP_MSG_ARRAY;
    if (op->length && (fixed ? count != op->length : count > op->length))
        return NULL;
    PyObject *copied = PyList_New(count);
    if (copied == NULL)
        return NULL;
    for (Py_ssize_t k = 0; k < count; k++) {
        PyObject *item = PyList_GET_ITEM(items, k), *value = NULL;
        if (op->sub != NULL)
            value = copy_message(item, op->sub);
        else if (PyUnicode_CheckExact(item))
            value = Py_NewRef(item);
        if (value == NULL) {
            Py_DECREF(copied);
            return NULL;
        }
        PyList_SET_ITEM(copied, k, value);
    }
    return copied;
}

/* A writable deep copy, built slot by slot. NULL with no error set means "not the common
   case": a value the generated constructor would convert or refuse, which copy() must see. */
static PyObject *copy_message(PyObject *message, const Type *type)
{
    if (!is_type(message, type) || !array_head_checked)
        return NULL;
    PyObject *copied = type->cls->tp_alloc(type->cls, 0);
    if (copied == NULL)
        return NULL;
    SLOT(copied, type->loan_offset) = Py_NewRef(Py_None);
    for (Py_ssize_t i = 0; i < type->nops; i++) {
        const Op *op = &type->ops[i];
        PyObject *value = SLOT(message, op->offset), *own = NULL;
        if (value == NULL) {
            Py_DECREF(copied);
            return NULL;
        }
        switch (op->kind) {
        case OP_PRIM:
            if (check_prim(value, op->prim) == 0)
                own = Py_NewRef(value);
            break;
        case OP_STRING:
            if (PyUnicode_CheckExact(value))
                own = Py_NewRef(value);
            break;
        case OP_NESTED:
            own = copy_message(value, op->sub);
            break;
        case OP_PRIM_ARRAY:
        case OP_PRIM_SEQ:
            if (check_array(value, op) == 0 && HEAD(value)->nd == 1)
                own = PyObject_CallMethodNoArgs(value, str_copy);
            break;
        default:
            own = copy_items(value, op);
            break;
        }
        if (own == NULL) {
            Py_DECREF(copied);
            return NULL;
        }
        SLOT(copied, op->offset) = own;
    }
    return copied;
}

/* ---------------------------------------------------------------------------------------- */
/* the Python object                                                                          */

enum { F_SIZE, F_ENCODE, F_SIZE_LEAN, F_ENCODE_LEAN, F_DECODE, F_VALIDATE, F_SEAL, F_COPY, F_COUNT };

typedef struct {
    PyObject_HEAD
    Type *type;
    int ros1;
    PyObject *frombuffer, *frozenlist;
    /* the generated Python functions this stands in for (None where it has none) */
    PyObject *fallback[F_COUNT];
} Codec;

static void codec_dealloc(Codec *self)
{
    type_free(self->type);
    Py_XDECREF(self->frombuffer);
    Py_XDECREF(self->frozenlist);
    for (int i = 0; i < F_COUNT; i++)
        Py_XDECREF(self->fallback[i]);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *codec_new(PyTypeObject *cls, PyObject *args, PyObject *kwargs)
{
    static char *names[] = {"program", "ros1", "frombuffer", "frozenlist", "size", "encode", "size_lean",
                            "encode_lean", "decode", "validate", "seal", "copy", NULL};
    PyObject *spec, *frombuffer, *frozenlist, *fallback[F_COUNT];
    int ros1;
    for (int i = 0; i < F_COUNT; i++)
        fallback[i] = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OpOO|$OOOOOOOO", names, &spec, &ros1, &frombuffer,
                                     &frozenlist, &fallback[0], &fallback[1], &fallback[2], &fallback[3],
                                     &fallback[4], &fallback[5], &fallback[6], &fallback[7]))
        return NULL;
    Codec *self = (Codec *)cls->tp_alloc(cls, 0);
    if (self == NULL)
        return NULL;
    self->type = type_from_spec(spec);
    if (self->type == NULL) {
        Py_DECREF(self);
        return NULL;
    }
    self->ros1 = ros1;
    self->frombuffer = Py_NewRef(frombuffer);
    self->frozenlist = Py_NewRef(frozenlist);
    for (int i = 0; i < F_COUNT; i++)
        self->fallback[i] = Py_NewRef(fallback[i]);
    return (PyObject *)self;
}

static PyObject *call_fallback(Codec *self, int which, PyObject *const *args, Py_ssize_t nargs)
{
    PyErr_Clear();
    if (self->fallback[which] == Py_None) {
        PyErr_SetString(PyExc_TypeError, "this codec has no such function");
        return NULL;
    }
    return PyObject_Vectorcall(self->fallback[which], args, nargs, NULL);
}

static PyObject *codec_sizes(Codec *self, PyObject *const *args, Py_ssize_t nargs, int lean)
{
    int which = lean ? F_SIZE_LEAN : F_SIZE;
    if (nargs != 1)
        return call_fallback(self, which, args, nargs);
    Out out = {NULL, 0, self->ros1};
    Py_ssize_t pos = 0;
    if (put_message(&out, &pos, self->type, args[0], lean) < 0)
        return call_fallback(self, which, args, nargs);
    return PyLong_FromSsize_t(pos);
}

static PyObject *codec_size(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    return codec_sizes(self, args, nargs, 0);
}

static PyObject *codec_size_lean(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    return codec_sizes(self, args, nargs, 1);
}

static PyObject *codec_encodes(Codec *self, PyObject *const *args, Py_ssize_t nargs, int lean)
{
    int which = lean ? F_ENCODE_LEAN : F_ENCODE;
    Py_ssize_t pos = 0;
    if (nargs < 2 || nargs > 3)
        return call_fallback(self, which, args, nargs);
    if (nargs == 3) {
        pos = PyLong_AsSsize_t(args[2]);
        if (pos == -1 && PyErr_Occurred())
            return call_fallback(self, which, args, nargs);
    }
    Py_buffer view;
    if (PyObject_GetBuffer(args[1], &view, PyBUF_WRITABLE) < 0)
        return call_fallback(self, which, args, nargs);
    Out out = {view.buf, view.len, self->ros1};
    int status = pos < 0 || pos > view.len ? REFUSE : put_message(&out, &pos, self->type, args[0], lean);
    PyBuffer_Release(&view);
    if (status < 0)
        return call_fallback(self, which, args, nargs);
    return PyLong_FromSsize_t(pos);
}

static PyObject *codec_encode(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    return codec_encodes(self, args, nargs, 0);
}

static PyObject *codec_encode_lean(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    return codec_encodes(self, args, nargs, 1);
}

static PyObject *codec_decode(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs < 1 || nargs > 3)
        return call_fallback(self, F_DECODE, args, nargs);
    Py_ssize_t pos = 0, end = -1;
    if (nargs >= 2 && (pos = PyLong_AsSsize_t(args[1])) == -1 && PyErr_Occurred())
        return call_fallback(self, F_DECODE, args, nargs);
    if (nargs == 3 && (end = PyLong_AsSsize_t(args[2])) == -1 && PyErr_Occurred())
        return call_fallback(self, F_DECODE, args, nargs);
    Py_buffer view;
    if (PyObject_GetBuffer(args[0], &view, PyBUF_SIMPLE) < 0)
        return call_fallback(self, F_DECODE, args, nargs);
    if (end < 0)
        end = view.len;
    PyObject *message = NULL;
    if (pos >= 0 && end <= view.len && pos <= end) {
        In in = {view.buf, end, self->ros1, args[0], self->frombuffer, self->frozenlist};
        message = get_message(&in, &pos, self->type);
    }
    PyBuffer_Release(&view);
    if (message == NULL)
        return call_fallback(self, F_DECODE, args, nargs);
    return message;
}

static PyObject *codec_validate(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs < 1 || nargs > 2 || check_message(args[0], self->type) < 0)
        return call_fallback(self, F_VALIDATE, args, nargs);
    Py_RETURN_NONE;
}

static PyObject *codec_seal(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2 || !PyLong_Check(args[1]) || !Py_IS_TYPE(args[0], self->type->cls) || seal_array_function == NULL) {
        if (nargs >= 1 && Py_IS_TYPE(args[0], self->type->frozen))
            return Py_NewRef(args[0]);
        return call_fallback(self, F_SEAL, args, nargs);
    }
    long callers = PyLong_AsLong(args[1]);
    if (callers < SEAL_FREEZE || callers > SEAL_KEEP)
        return call_fallback(self, F_SEAL, args, nargs);
    if (seal_message(args[0], self->type, (int)callers, args[1]) < 0)
        return NULL;
    return Py_NewRef(args[0]);
}

static PyObject *codec_copy(Codec *self, PyObject *const *args, Py_ssize_t nargs)
{
    PyObject *copied = nargs == 1 ? copy_message(args[0], self->type) : NULL;
    if (copied == NULL)
        return call_fallback(self, F_COPY, args, nargs);
    return copied;
}

static PyMethodDef codec_methods[] = {
    {"seal", (PyCFunction)(void (*)(void))codec_seal, METH_FASTCALL,
     "seal(message, callers) -> message, frozen in place as the generated sealer does"},
    {"validate", (PyCFunction)(void (*)(void))codec_validate, METH_FASTCALL,
     "validate(message, where='') -> None; what it does not accept as it is goes to the generated validator"},
    {"size", (PyCFunction)(void (*)(void))codec_size, METH_FASTCALL, "size(message) -> bytes of its body"},
    {"encode", (PyCFunction)(void (*)(void))codec_encode, METH_FASTCALL,
     "encode(message, buffer, pos=0) -> end: the body written at pos"},
    {"size_lean", (PyCFunction)(void (*)(void))codec_size_lean, METH_FASTCALL,
     "size_lean(message): the size with top-level primitive sequences left empty"},
    {"encode_lean", (PyCFunction)(void (*)(void))codec_encode_lean, METH_FASTCALL,
     "encode_lean(message, buffer, pos=0) -> end, top-level primitive sequences left empty"},
    {"copy", (PyCFunction)(void (*)(void))codec_copy, METH_FASTCALL,
     "copy(message) -> a deep, writable copy, as hetros.msg.copy makes it"},
    {"decode", (PyCFunction)(void (*)(void))codec_decode, METH_FASTCALL,
     "decode(buffer, pos=0, end=-1) -> a read-only message; primitive arrays are views on buffer"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject CodecType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "hetros.msg._ccdr.Codec",
    .tp_doc = "The compiled codec of one message type (falls back to the generated Python functions).",
    .tp_basicsize = sizeof(Codec),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = codec_new,
    .tp_dealloc = (destructor)codec_dealloc,
    .tp_methods = codec_methods,
};

/* Whether ArrayHead matches this numpy: ``owner`` is a fresh writable 1-d array of ``length``
   elements at ``address`` with ``dtype``, ``view`` a read-only view of it. */
static int array_head_matches(PyObject *owner, PyObject *view, unsigned long long address, Py_ssize_t length,
                              PyObject *dtype)
{
    if (ndarray_type == NULL || !Py_IS_TYPE(owner, ndarray_type) || !Py_IS_TYPE(view, ndarray_type))
        return 0;
    ArrayHead *o = HEAD(owner), *v = HEAD(view);
    return o->data == (char *)(uintptr_t)address && o->nd == 1 && o->dimensions[0] == length && o->base == NULL
           && o->descr == dtype && (o->flags & ARRAY_WRITEABLE) && v->base == owner && v->nd == 1
           && v->dimensions[0] == length && v->descr == dtype && !(v->flags & ARRAY_WRITEABLE);
}

static PyObject *configure(PyObject *module, PyObject *args)
{
    (void)module;
    PyObject *loan_buffer, *seal_array, *frozenlist, *owner, *view, *dtype;
    unsigned long long address;
    Py_ssize_t length;
    if (!PyArg_ParseTuple(args, "O!OO!OOKnO", &PyType_Type, &loan_buffer, &seal_array, &PyType_Type, &frozenlist,
                          &owner, &view, &address, &length, &dtype))
        return NULL;
    Py_XSETREF(loan_buffer_type, (PyTypeObject *)Py_NewRef(loan_buffer));
    Py_XSETREF(seal_array_function, Py_NewRef(seal_array));
    Py_XSETREF(frozenlist_type, Py_NewRef(frozenlist));
    array_head_checked = array_head_matches(owner, view, address, length, dtype);
    return PyBool_FromLong(array_head_checked);
}

static PyMethodDef module_functions[] = {
    {"configure", configure, METH_VARARGS,
     "configure(LoanBuffer, _seal_array, FrozenList, owner, view, address, length, dtype): what sealing needs "
     "of hetros.msg._message, and a probe array and its read-only view; returns whether numpy's array head "
     "is read directly"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "hetros.msg._ccdr", "The compiled CDR / ROS 1 codec interpreter.", -1, module_functions,
};

PyMODINIT_FUNC PyInit__ccdr(void)
{
    if (PyType_Ready(&CodecType) < 0)
        return NULL;
    PyObject *mod = PyModule_Create(&module);
    if (mod == NULL)
        return NULL;
    if (PyModule_AddObjectRef(mod, "Codec", (PyObject *)&CodecType) < 0)
        goto fail;
    str_dtype = PyUnicode_InternFromString("dtype");
    str_size = PyUnicode_InternFromString("size");
    str_base = PyUnicode_InternFromString("base");
    str_flags = PyUnicode_InternFromString("flags");
    str_writeable = PyUnicode_InternFromString("writeable");
    str_hetros_seal = PyUnicode_InternFromString("_hetros_seal");
    str_copy = PyUnicode_InternFromString("copy");
    if (str_copy == NULL || str_base == NULL || str_flags == NULL || str_writeable == NULL || str_hetros_seal == NULL)
        goto fail;
    PyObject *numpy = PyImport_ImportModule("numpy");
    if (str_dtype == NULL || str_size == NULL || numpy == NULL)
        goto fail;
    ndarray_type = (PyTypeObject *)PyObject_GetAttrString(numpy, "ndarray"); /* kept for the process' life */
    Py_DECREF(numpy);
    if (ndarray_type == NULL || !PyType_Check(ndarray_type))
        goto fail;
    return mod;
fail:
    Py_DECREF(mod);
    return NULL;
}

/*
 * hetros.transport.shm._cslot: the bytes of a shared-memory slot as a buffer that keeps its
 * sample alive.
 *
 * A received sample goes back to iceoryx2 when its Python object dies; every view and numpy
 * array made from a slot must therefore hold the sample. ``Memory`` is that holder: a
 * buffer over (address, size) that keeps ``keepalive`` (the sample) and, when given a
 * list, counts itself in it while it lives (the reader's count of borrowed samples). The
 * pure-Python fallback (_sample.py) builds the same from a ctypes array type per size.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

typedef struct {
    PyObject_HEAD
    char *address;
    Py_ssize_t size;
    int readonly;
    PyObject *keepalive;
    PyObject *borrowed; /* a list with one entry per live Memory, or NULL */
} Memory;

static PyObject *memory_new(PyTypeObject *cls, PyObject *args, PyObject *kwargs)
{
    static char *names[] = {"address", "size", "keepalive", "borrowed", "readonly", NULL};
    unsigned long long address;
    Py_ssize_t size;
    PyObject *keepalive, *borrowed = Py_None;
    int readonly = 1;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "KnO|Op", names, &address, &size, &keepalive, &borrowed,
                                     &readonly))
        return NULL;
    if (address == 0 || size < 0) {
        PyErr_Format(PyExc_ValueError, "a slot must have an address and a size >= 0, not %llu and %zd", address, size);
        return NULL;
    }
    if (borrowed != Py_None && !PyList_Check(borrowed)) {
        PyErr_Format(PyExc_TypeError, "borrowed must be a list or None, not %R", borrowed);
        return NULL;
    }
    Memory *self = (Memory *)cls->tp_alloc(cls, 0);
    if (self == NULL)
        return NULL;
    if (borrowed != Py_None) {
        if (PyList_Append(borrowed, Py_None) < 0) {
            Py_DECREF(self);
            return NULL;
        }
        self->borrowed = Py_NewRef(borrowed);
    }
    self->address = (char *)(uintptr_t)address;
    self->size = size;
    self->readonly = readonly;
    self->keepalive = Py_NewRef(keepalive);
    return (PyObject *)self;
}

static void memory_dealloc(Memory *self)
{
    if (self->borrowed != NULL) {
        Py_ssize_t count = PyList_GET_SIZE(self->borrowed);
        if (count > 0 && PyList_SetSlice(self->borrowed, count - 1, count, NULL) < 0)
            PyErr_WriteUnraisable((PyObject *)self);
        Py_DECREF(self->borrowed);
    }
    Py_XDECREF(self->keepalive);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int memory_getbuffer(Memory *self, Py_buffer *view, int flags)
{
    return PyBuffer_FillInfo(view, (PyObject *)self, self->address, self->size, self->readonly, flags);
}

static PyBufferProcs memory_as_buffer = {
    .bf_getbuffer = (getbufferproc)memory_getbuffer,
};

static Py_ssize_t memory_length(Memory *self)
{
    return self->size;
}

static PySequenceMethods memory_as_sequence = {
    .sq_length = (lenfunc)memory_length,
};

static PyTypeObject MemoryType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "hetros.transport.shm._cslot.Memory",
    .tp_doc = "Memory(address, size, keepalive, borrowed=None, readonly=True): a slot's bytes as a buffer.",
    .tp_basicsize = sizeof(Memory),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = memory_new,
    .tp_dealloc = (destructor)memory_dealloc,
    .tp_as_buffer = &memory_as_buffer,
    .tp_as_sequence = &memory_as_sequence,
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "hetros.transport.shm._cslot", "Shared-memory slots as buffers that hold their sample.",
    -1, NULL,
};

PyMODINIT_FUNC PyInit__cslot(void)
{
    if (PyType_Ready(&MemoryType) < 0)
        return NULL;
    PyObject *mod = PyModule_Create(&module);
    if (mod == NULL)
        return NULL;
    if (PyModule_AddObjectRef(mod, "Memory", (PyObject *)&MemoryType) < 0) {
        Py_DECREF(mod);
        return NULL;
    }
    return mod;
}

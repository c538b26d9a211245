/*
 * hetros.transport.shm._cslot: the compiled hot path of the shared-memory transport.
 *
 * ``Memory`` is the bytes of a slot as a buffer that keeps its sample alive. A received
 * sample goes back to iceoryx2 when its Python object dies; every view and numpy array made
 * from a slot must therefore hold the sample. ``Memory`` is that holder: a buffer over
 * (address, size) that keeps ``keepalive`` (the sample) and, when given a list, counts itself
 * in it while it lives (the reader's count of borrowed samples). The pure-Python fallback
 * (_sample.py) builds the same from a ctypes array type per size.
 *
 * ``send_cdr`` and ``take_cdr`` are the common case of ``Service.send_cdr`` and
 * ``ShmReader._take_from`` (_service.py, _endpoints.py), which stay the reference: they run
 * without a compiler and do every case these decline. These read and write the state of
 * those Python objects (sequence numbers, room, expected sequence) so there is one state
 * and one set of rules; the sample layout and credits offsets come from ``configure``.
 * Whatever is unusual (no room, a stale wake list, a gap, a waiting publisher, a damaged
 * sample) is handed back before it has any effect the Python code would not also have had.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <time.h>
#include <structmember.h>

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

/* -- the hot path of publishing and taking --------------------------------------------- */

enum { NOT_HANDLED = 0, SENT = 1, SENT_STALE_WAKES = 2 };

static PyObject *loan_slice_function, *assume_init_function;
static Py_ssize_t header_size = -1, cdr_body_at, credits_head, slot_words, subscriber_slots, borrow_limit;
static PyObject *str_publisher, *str_credits_at, *str_blocking, *str_room, *str_next_seq, *str_wakes_version,
    *str_wakes, *str_payload_ptr, *str_send, *str_receive, *str_header, *str_number_of_elements, *str_subscriber,
    *str_service, *str_expected, *str_suspect_since, *str_depth, *str_qos;

static const char CDR_LE[4] = {0, 1, 0, 0};

/* The iceoryx2 data segments this process has mapped (MappedSegments in _sample.py), sorted by
   address: a received sample's size comes from shared memory, so a sample is used only when it
   lies inside one of them (found by binary search; a graph of 1,000 topics maps over 1,000);
   the ranges are asked for again (``mapped_refresh``) when it does not. */
static uintptr_t *mapped_low, *mapped_high;
static Py_ssize_t mapped_count, mapped_capacity, mapped_last;
static PyObject *mapped_refresh;

static int in_mapped(uintptr_t address, unsigned long long size)
{
    Py_ssize_t i = mapped_last;
    if (i < mapped_count && address >= mapped_low[i] && size <= (unsigned long long)(mapped_high[i] - address))
        return 1;
    Py_ssize_t low = 0, high = mapped_count; /* the last range starting at or below address */
    while (low < high) {
        Py_ssize_t middle = low + (high - low) / 2;
        if (mapped_low[middle] <= address)
            low = middle + 1;
        else
            high = middle;
    }
    i = low - 1;
    if (i >= 0 && size <= (unsigned long long)(mapped_high[i] - address)) {
        mapped_last = i;
        return 1;
    }
    return 0;
}

/* 1: inside a mapped segment; 0: not (after asking for the ranges again); -1: error */
static int sample_mapped(uintptr_t address, unsigned long long size)
{
    if (in_mapped(address, size))
        return 1;
    if (mapped_refresh == NULL)
        return 0;
    PyObject *ranges = PyObject_CallNoArgs(mapped_refresh);
    if (ranges == NULL)
        return -1;
    PyObject *fast = PySequence_Fast(ranges, "mapped_refresh() must return a sorted list of (low, high)");
    Py_DECREF(ranges);
    if (fast == NULL)
        return -1;
    Py_ssize_t count = PySequence_Fast_GET_SIZE(fast);
    if (count > mapped_capacity) {
        uintptr_t *lows = PyMem_Realloc(mapped_low, (size_t)count * sizeof(uintptr_t));
        if (lows != NULL)
            mapped_low = lows;
        uintptr_t *highs = lows == NULL ? NULL : PyMem_Realloc(mapped_high, (size_t)count * sizeof(uintptr_t));
        if (highs == NULL) {
            Py_DECREF(fast);
            PyErr_NoMemory();
            return -1;
        }
        mapped_high = highs;
        mapped_capacity = count;
    }
    mapped_count = 0;
    mapped_last = 0;
    for (Py_ssize_t i = 0; i < count; i++) {
        unsigned long long low, high;
        if (!PyArg_ParseTuple(PySequence_Fast_GET_ITEM(fast, i), "KK", &low, &high)) {
            Py_DECREF(fast);
            return -1;
        }
        mapped_low[mapped_count] = (uintptr_t)low;
        mapped_high[mapped_count] = (uintptr_t)high;
        mapped_count++;
    }
    Py_DECREF(fast);
    return in_mapped(address, size);
}

static PyObject *configure(PyObject *module, PyObject *args)
{
    (void)module;
    PyObject *loan_slice, *assume_init, *refresh;
    Py_ssize_t header, body_at, head, words, slots, limit;
    if (!PyArg_ParseTuple(args, "OOnnnnnnO", &loan_slice, &assume_init, &header, &body_at, &head, &words, &slots,
                          &limit, &refresh))
        return NULL;
    if (header < 16 || body_at != header + 4 || head < 3 || words < 2 || slots < 1 || limit < 2) {
        PyErr_Format(PyExc_ValueError, "the sample header must be at least 16 bytes with the CDR body 4 bytes after "
                     "it, not %zd and %zd", header, body_at);
        return NULL;
    }
    Py_XSETREF(loan_slice_function, Py_NewRef(loan_slice));
    Py_XSETREF(assume_init_function, Py_NewRef(assume_init));
    Py_XSETREF(mapped_refresh, Py_NewRef(refresh));
    header_size = header;
    cdr_body_at = body_at;
    credits_head = head;
    slot_words = words;
    subscriber_slots = slots;
    borrow_limit = limit;
    Py_RETURN_NONE;
}

/* The slots of the state classes (``Service``, ``_Port``) that the hot path reads and writes,
   found by ``bind_slots``: read and written in place, as the classes' own member descriptors
   do, instead of through a name lookup each (a dozen per message). An object of another
   class, or an empty slot, goes through the attribute protocol. */
#define SLOT(obj, offset) (*(PyObject **)((char *)(obj) + (offset)))
static struct {
    PyObject *name;
    PyTypeObject *owner;
    Py_ssize_t offset;
} bound_slots[32];
static int bound_count;

static PyObject *get_attr(PyObject *obj, PyObject *name)
{
    for (int i = 0; i < bound_count; i++)
        if (bound_slots[i].name == name && Py_IS_TYPE(obj, bound_slots[i].owner)) {
            PyObject *value = SLOT(obj, bound_slots[i].offset);
            if (value != NULL)
                return Py_NewRef(value);
            break;
        }
    return PyObject_GetAttr(obj, name);
}

static int set_attr(PyObject *obj, PyObject *name, PyObject *value)
{
    for (int i = 0; i < bound_count; i++)
        if (bound_slots[i].name == name && Py_IS_TYPE(obj, bound_slots[i].owner)) {
            Py_XSETREF(SLOT(obj, bound_slots[i].offset), Py_NewRef(value));
            return 0;
        }
    return PyObject_SetAttr(obj, name, value);
}

/* bind_slots(cls): remember where cls keeps each attribute the hot path uses that is a slot */
static PyObject *bind_slots(PyObject *module, PyObject *cls)
{
    (void)module;
    if (!PyType_Check(cls)) {
        PyErr_Format(PyExc_TypeError, "bind_slots takes a class, not %R", cls);
        return NULL;
    }
    PyObject *names[] = {str_publisher, str_credits_at, str_blocking, str_room, str_next_seq, str_wakes_version,
                         str_wakes, str_subscriber, str_service, str_expected, str_suspect_since, str_qos};
    int bound = 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        PyObject *descr = PyObject_GetAttr(cls, names[i]);
        if (descr == NULL) {
            PyErr_Clear();
            continue;
        }
        int is_slot = Py_IS_TYPE(descr, &PyMemberDescr_Type) &&
                      ((PyMemberDescrObject *)descr)->d_member->type == T_OBJECT_EX &&
                      PyType_IsSubtype((PyTypeObject *)cls, PyDescr_TYPE(descr));
        bound += is_slot;
        for (int k = 0; k < bound_count && is_slot; k++)
            is_slot = bound_slots[k].name != names[i] || bound_slots[k].owner != (PyTypeObject *)cls;
        if (is_slot) { /* and not bound before */
            if (bound_count >= (int)(sizeof bound_slots / sizeof bound_slots[0])) {
                Py_DECREF(descr);
                PyErr_SetString(PyExc_OverflowError, "too many slots bound");
                return NULL;
            }
            bound_slots[bound_count].name = names[i];
            bound_slots[bound_count].owner = (PyTypeObject *)Py_NewRef(cls); /* kept for the process' life */
            bound_slots[bound_count].offset = ((PyMemberDescrObject *)descr)->d_member->offset;
            bound_count++;
        }
        Py_DECREF(descr);
    }
    return PyLong_FromLong(bound);
}

/* An int attribute of obj as signed 64 bits; -1 with an exception set on failure */
static int get_i64(PyObject *obj, PyObject *name, long long *value)
{
    PyObject *attr = get_attr(obj, name);
    if (attr == NULL)
        return -1;
    *value = PyLong_AsLongLong(attr);
    Py_DECREF(attr);
    return *value == -1 && PyErr_Occurred() ? -1 : 0;
}

/* The same for a count or an address (user-space addresses are below 2**63) */
/* a size read from shared memory: any unsigned 64-bit value (a forged one is refused later) */
static int get_size(PyObject *obj, PyObject *name, unsigned long long *value)
{
    PyObject *number = PyObject_GetAttr(obj, name);
    if (number == NULL)
        return -1;
    *value = PyLong_AsUnsignedLongLong(number);
    Py_DECREF(number);
    return *value == (unsigned long long)-1 && PyErr_Occurred() ? -1 : 0;
}

static int get_u64(PyObject *obj, PyObject *name, unsigned long long *value)
{
    long long number;
    if (get_i64(obj, name, &number) < 0)
        return -1;
    if (number < 0) {
        PyErr_Format(PyExc_ValueError, "%U must be at least 0, not %lld", name, number);
        return -1;
    }
    *value = (unsigned long long)number;
    return 0;
}

/* A truth attribute of obj: 1, 0, or -1 with an exception set */
static int get_flag(PyObject *obj, PyObject *name)
{
    PyObject *attr = get_attr(obj, name);
    if (attr == NULL)
        return -1;
    int flag = PyObject_IsTrue(attr);
    Py_DECREF(attr);
    return flag;
}

/* A float attribute of obj; -1.0 with an exception set on failure */
static double get_double(PyObject *obj, PyObject *name)
{
    PyObject *attr = get_attr(obj, name);
    if (attr == NULL)
        return -1.0;
    double value = PyFloat_AsDouble(attr);
    Py_DECREF(attr);
    return value;
}

static int set_i64(PyObject *obj, PyObject *name, long long value)
{
    PyObject *number = PyLong_FromLongLong(value);
    if (number == NULL)
        return -1;
    int status = set_attr(obj, name, number);
    Py_DECREF(number);
    return status;
}

static PyObject *call_method0(PyObject *obj, PyObject *name)
{
    return PyObject_VectorcallMethod(name, &obj, 1 | PY_VECTORCALL_ARGUMENTS_OFFSET, NULL);
}

/* Sends a reliable keep_all publisher can make before a subscriber's FIFO may be full: depth
   less the fullest live FIFO, as ``Service.wait_for_space`` counts it when no FIFO is full;
   0 when one is (the reference path then waits, and checks whether that subscriber lives). */
static long long room_left(uint64_t *credits, uint64_t published, long long depth)
{
    long long fullest = 0;
    for (Py_ssize_t slot = 0; slot < subscriber_slots; slot++) {
        uint64_t *words = credits + credits_head + slot_words * slot;
        if (__atomic_load_n(&words[1], __ATOMIC_ACQUIRE) == 0) /* no live subscriber (pid 0) */
            continue;
        long long fill = (long long)(published - __atomic_load_n(&words[0], __ATOMIC_ACQUIRE));
        if (fill >= depth)
            return 0;
        if (fill > fullest)
            fullest = fill;
    }
    if (__atomic_load_n(&credits[1], __ATOMIC_ACQUIRE) != 0)
        __atomic_store_n(&credits[1], 0, __ATOMIC_SEQ_CST); /* nobody waits any more */
    return depth - fullest;
}

/* Whether the compiled path may send on ``service`` now: 1 (with its publisher in *publisher,
   a new reference, and the room it counted), 0 when the reference path must (no publisher
   yet, or a full reliable FIFO to wait for), -1 with an exception set. */
static int may_send(PyObject *service, PyObject **publisher, unsigned long long *credits_at, int *blocking,
                    long long *room)
{
    *publisher = NULL;
    *room = 0;
    if (get_u64(service, str_credits_at, credits_at) < 0)
        return -1;
    *publisher = get_attr(service, str_publisher);
    if (*publisher == NULL)
        return -1;
    *blocking = get_flag(service, str_blocking);
    if (*blocking < 0 || (*blocking && get_i64(service, str_room, room) < 0))
        goto error;
    if (*blocking && *room <= 0 && *credits_at != 0) {
        unsigned long long next_seq;
        long long depth = -1;
        PyObject *qos = get_attr(service, str_qos); /* the rare path: room used up */
        int failed = qos == NULL || get_i64(qos, str_depth, &depth) < 0 ||
                     get_u64(service, str_next_seq, &next_seq) < 0;
        Py_XDECREF(qos);
        if (failed)
            goto error;
        *room = room_left((uint64_t *)(uintptr_t)*credits_at, (uint64_t)next_seq - 1, depth);
        if (*room > 0 && set_i64(service, str_room, *room) < 0)
            goto error;
    }
    if (*publisher == Py_None || *credits_at == 0 || (*blocking && *room <= 0)) {
        Py_CLEAR(*publisher);
        return 0;
    }
    return 1;
error:
    Py_CLEAR(*publisher);
    return -1;
}

/* Stamp the header of the loaned ``sample`` (its payload at ``slot``), send it, publish its
   sequence number in the credits and wake the subscribers, as ``Service.send`` does:
   SENT, SENT_STALE_WAKES (the reference path must reread who to wake), or NULL. */
static PyObject *stamp_and_send(PyObject *service, PyObject *sample, char *slot, uint32_t layout,
                                unsigned long publisher_slot, unsigned long long credits_at, int blocking,
                                long long room)
{
    if (blocking && set_i64(service, str_room, room - 1) < 0)
        return NULL;
    unsigned long long seq;
    if (get_u64(service, str_next_seq, &seq) < 0)
        return NULL;
    uint32_t words[2] = {(uint32_t)publisher_slot, layout};
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now); /* when it was sent: a subscriber's lifespan is checked against it */
    uint64_t sent_ns = (uint64_t)now.tv_sec * 1000000000u + (uint64_t)now.tv_nsec;
    memcpy(slot, &seq, 8);
    memcpy(slot + 8, words, 8);
    memcpy(slot + 16, &sent_ns, 8);
    memset(slot + 24, 0, (size_t)(header_size - 24));
    PyObject *initialized = PyObject_Vectorcall(assume_init_function, &sample, 1, NULL);
    if (initialized == NULL)
        return NULL;
    PyObject *sent = call_method0(initialized, str_send);
    Py_DECREF(initialized);
    if (sent == NULL)
        return NULL;
    Py_DECREF(sent);
    if (set_i64(service, str_next_seq, (long long)seq + 1) < 0)
        return NULL;
    uint64_t *credits = (uint64_t *)(uintptr_t)credits_at;
    __atomic_store_n(&credits[0], (uint64_t)seq, __ATOMIC_RELEASE);
    uint64_t version = __atomic_load_n(&credits[2], __ATOMIC_ACQUIRE);
    long long known; /* -1 before the first wake list */
    if (get_i64(service, str_wakes_version, &known) < 0)
        return NULL;
    if (known < 0 || (uint64_t)known != version)
        return PyLong_FromLong(SENT_STALE_WAKES);
    PyObject *wakes = get_attr(service, str_wakes);
    if (wakes == NULL)
        return NULL;
    if (!PyList_Check(wakes)) {
        Py_DECREF(wakes);
        return PyLong_FromLong(SENT_STALE_WAKES);
    }
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(wakes); i++) {
        PyObject *wake = PyList_GET_ITEM(wakes, i);
        if (!PyTuple_Check(wake) || PyTuple_GET_SIZE(wake) != 2) {
            Py_DECREF(wakes);
            PyErr_Format(PyExc_TypeError, "a wake must be (notify, event id), not %R", wake);
            return NULL;
        }
        PyObject *result = PyObject_Vectorcall(PyTuple_GET_ITEM(wake, 0), &PyTuple_GET_ITEM(wake, 1), 1, NULL);
        if (result == NULL) {
            Py_DECREF(wakes);
            return NULL;
        }
        Py_DECREF(result);
    }
    Py_DECREF(wakes);
    return PyLong_FromLong(SENT);
}

/* send_cdr(service, message, body_size, encode_body, publisher_slot), the service's lock held */
static PyObject *send_cdr(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    (void)module;
    if (nargs != 5 || header_size < 0) {
        PyErr_SetString(PyExc_TypeError, "send_cdr(service, message, body_size, encode_body, publisher_slot) "
                        "after configure()");
        return NULL;
    }
    PyObject *service = args[0];
    Py_ssize_t body_size = PyLong_AsSsize_t(args[2]);
    unsigned long publisher_slot = PyLong_AsUnsignedLong(args[4]);
    if (PyErr_Occurred())
        return NULL;
    PyObject *publisher;
    unsigned long long credits_at;
    int blocking;
    long long room;
    int may = may_send(service, &publisher, &credits_at, &blocking, &room);
    if (may <= 0)
        return may < 0 ? NULL : PyLong_FromLong(NOT_HANDLED);
    Py_ssize_t size = cdr_body_at + body_size;
    PyObject *size_obj = PyLong_FromSsize_t(size);
    if (size_obj == NULL) {
        Py_DECREF(publisher);
        return NULL;
    }
    PyObject *loan_args[2] = {publisher, size_obj};
    PyObject *sample = PyObject_Vectorcall(loan_slice_function, loan_args, 2, NULL);
    Py_DECREF(size_obj);
    Py_DECREF(publisher);
    if (sample == NULL)
        return NULL;
    PyObject *status = NULL;
    unsigned long long address;
    if (get_u64(sample, str_payload_ptr, &address) < 0)
        goto done;
    char *slot = (char *)(uintptr_t)address;
    PyObject *memory = PyMemoryView_FromMemory(slot, size, PyBUF_WRITE);
    PyObject *at = PyLong_FromSsize_t(cdr_body_at);
    if (memory == NULL || at == NULL) {
        Py_XDECREF(memory);
        Py_XDECREF(at);
        goto done;
    }
    memcpy(slot + header_size, CDR_LE, 4);
    PyObject *encode_args[3] = {args[1], memory, at};
    PyObject *end = PyObject_Vectorcall(args[3], encode_args, 3, NULL);
    Py_DECREF(memory);
    Py_DECREF(at);
    if (end == NULL)
        goto done;
    Py_DECREF(end);
    status = stamp_and_send(service, sample, slot, 0 /* the CDR layout */, publisher_slot, credits_at, blocking,
                            room);
done:
    Py_DECREF(sample);
    return status;
}

/* send_slot(service, sample, layout, publisher_slot), the service's lock held: a slot loaned
   and filled by the reference path (the split layout), sent as ``Service.send`` sends it */
static PyObject *send_slot(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    (void)module;
    if (nargs != 4 || header_size < 0) {
        PyErr_SetString(PyExc_TypeError, "send_slot(service, sample, layout, publisher_slot) after configure()");
        return NULL;
    }
    PyObject *service = args[0], *sample = args[1];
    unsigned long layout = PyLong_AsUnsignedLong(args[2]);
    unsigned long publisher_slot = PyLong_AsUnsignedLong(args[3]);
    if (PyErr_Occurred())
        return NULL;
    PyObject *publisher;
    unsigned long long credits_at, address;
    int blocking;
    long long room;
    int may = may_send(service, &publisher, &credits_at, &blocking, &room);
    if (may <= 0)
        return may < 0 ? NULL : PyLong_FromLong(NOT_HANDLED);
    Py_DECREF(publisher);
    if (get_u64(sample, str_payload_ptr, &address) < 0)
        return NULL;
    return stamp_and_send(service, sample, (char *)(uintptr_t)address, (uint32_t)layout, publisher_slot, credits_at,
                          blocking, room);
}

/* Nothing received: None when that is surely all (nothing published past what the port
   expects, no suspicion pending: what a polling loop meets), else False for the reference
   path's check of a publisher iceoryx2 may have failed to connect. */
static PyObject *nothing_taken(PyObject *port)
{
    PyObject *service = get_attr(port, str_service);
    if (service == NULL)
        return NULL;
    int blocking = get_flag(service, str_blocking);
    unsigned long long credits_at = 0, expected = 0;
    int failed = blocking < 0 || get_u64(service, str_credits_at, &credits_at) < 0 ||
                 get_u64(port, str_expected, &expected) < 0;
    Py_DECREF(service);
    if (failed)
        return NULL;
    if (!blocking)
        Py_RETURN_NONE;
    double since = get_double(port, str_suspect_since);
    if (PyErr_Occurred())
        return NULL;
    if (since == 0.0 && credits_at != 0 &&
        __atomic_load_n((uint64_t *)(uintptr_t)credits_at, __ATOMIC_ACQUIRE) < expected)
        Py_RETURN_NONE;
    Py_RETURN_FALSE;
}

/* take_cdr(port, subscriber_slot, copies, borrowed, decode_body), the reader's lock held.

   Returns the decoded message; None when nothing is there (False: see nothing_taken); or
   (memory, size) for the reference path to finish when the sample is anything but the
   common case. */
static PyObject *take_cdr(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    (void)module;
    if (nargs != 5 || header_size < 0 || !PyList_Check(args[3])) {
        PyErr_SetString(PyExc_TypeError, "take_cdr(port, subscriber_slot, copies, borrowed: list, decode_body) "
                        "after configure()");
        return NULL;
    }
    PyObject *port = args[0], *borrowed = args[3];
    Py_ssize_t subscriber_slot = PyLong_AsSsize_t(args[1]);
    int copies = PyObject_IsTrue(args[2]);
    if (PyErr_Occurred())
        return NULL;
    PyObject *subscriber = get_attr(port, str_subscriber);
    if (subscriber == NULL)
        return NULL;
    PyObject *sample = call_method0(subscriber, str_receive);
    Py_DECREF(subscriber);
    if (sample == Py_None) {
        Py_DECREF(sample);
        return nothing_taken(port);
    }
    if (sample == NULL)
        return NULL;
    PyObject *header = PyObject_GetAttr(sample, str_header);
    unsigned long long size = 0, address = 0;
    int failed = header == NULL || get_size(header, str_number_of_elements, &size) < 0 ||
                 get_u64(sample, str_payload_ptr, &address) < 0;
    Py_XDECREF(header);
    if (failed)
        goto error_sample;
    int mapped = sample_mapped((uintptr_t)address, size);
    if (mapped < 0)
        goto error_sample;
    if (!mapped) { /* its size runs past its segment: released unread, the reference path counts it */
        Py_DECREF(sample);
        return Py_BuildValue("(OK)", Py_None, size);
    }
    char *slot = (char *)(uintptr_t)address;
    int common = (Py_ssize_t)size >= cdr_body_at && (Py_ssize_t)size <= PY_SSIZE_T_MAX &&
                 PyList_GET_SIZE(borrowed) < borrow_limit - 2;
    unsigned long long seq = 0, expected = 0, credits_at = 0;
    uint32_t layout = 0;
    PyObject *service = NULL;
    if (common) {
        memcpy(&seq, slot, 8);
        memcpy(&layout, slot + 12, 4);
        /* the CDR layout, little endian; or the split layout, whose accounting is the same */
        common = (layout == 0 && slot[header_size + 1] == 1) || layout == 1;
    }
    if (common) {
        double since = get_double(port, str_suspect_since);
        service = get_attr(port, str_service);
        if (PyErr_Occurred() || service == NULL || get_u64(port, str_expected, &expected) < 0 ||
            get_u64(service, str_credits_at, &credits_at) < 0)
            goto error_service;
        uint64_t *credits = (uint64_t *)(uintptr_t)credits_at;
        /* else the reference path: a gap (a blocking topic's loss; a keep_last topic's overwritten
           messages, which it counts) or a message from before this reader joined */
        common = since == 0.0 && credits_at != 0 && seq == expected;
        if (common) {
            if (set_i64(port, str_expected, (long long)seq + 1) < 0)
                goto error_service;
            /* taken, then waiting, in this order (as the publisher announces, then rereads):
               a publisher that waits for room is the reference path's to wake, which
               repeats these two steps harmlessly */
            __atomic_store_n(&credits[credits_head + slot_words * subscriber_slot], (uint64_t)seq, __ATOMIC_SEQ_CST);
            common = __atomic_load_n(&credits[1], __ATOMIC_SEQ_CST) == 0;
        }
        Py_CLEAR(service);
    }
    PyObject *memory;
    if (common && copies && layout == 0) {
        /* the message will keep nothing of the sample: it goes back once decoded */
        memory = PyMemoryView_FromMemory(slot, (Py_ssize_t)size, PyBUF_READ);
    } else {
        Memory *leased = (Memory *)MemoryType.tp_alloc(&MemoryType, 0);
        if (leased == NULL || PyList_Append(borrowed, Py_None) < 0) {
            Py_XDECREF(leased);
            goto error_sample;
        }
        leased->borrowed = Py_NewRef(borrowed);
        leased->address = slot;
        leased->size = (Py_ssize_t)size;
        leased->readonly = 1;
        leased->keepalive = Py_NewRef(sample);
        memory = PyMemoryView_FromObject((PyObject *)leased);
        Py_DECREF(leased);
    }
    if (memory == NULL)
        goto error_sample;
    if (!common || layout != 0) {
        Py_DECREF(sample);
        if (common) /* accounted for: the split layout's arrays are left to the reference decoder */
            return Py_BuildValue("(NKI)", memory, size, layout);
        PyObject *unusual = Py_BuildValue("(NK)", memory, size);
        return unusual;
    }
    PyObject *decode_args[3] = {memory, PyLong_FromSsize_t(cdr_body_at), PyLong_FromUnsignedLongLong(size)};
    PyObject *message = NULL;
    if (decode_args[1] != NULL && decode_args[2] != NULL)
        message = PyObject_Vectorcall(args[4], decode_args, 3, NULL);
    Py_XDECREF(decode_args[1]);
    Py_XDECREF(decode_args[2]);
    Py_DECREF(memory);
    Py_DECREF(sample);
    return message;

error_service:
    Py_XDECREF(service);
error_sample:
    Py_DECREF(sample);
    return NULL;
}

static PyMethodDef module_functions[] = {
    {"configure", configure, METH_VARARGS,
     "configure(loan_slice, assume_init, header_size, cdr_body_at, credits_head, slot_words, subscriber_slots, "
     "borrow_limit, mapped_refresh)"},
    {"bind_slots", bind_slots, METH_O,
     "bind_slots(cls) -> how many of the attributes the hot path uses are slots of cls, read in place from now on"},
    {"send_cdr", (PyCFunction)(void (*)(void))send_cdr, METH_FASTCALL,
     "send_cdr(service, message, body_size, encode_body, publisher_slot) -> 0 not handled, 1 sent, "
     "2 sent but the wake list is stale"},
    {"send_slot", (PyCFunction)(void (*)(void))send_slot, METH_FASTCALL,
     "send_slot(service, sample, layout, publisher_slot) -> 0 not handled, 1 sent, 2 sent but the wake list is "
     "stale"},
    {"take_cdr", (PyCFunction)(void (*)(void))take_cdr, METH_FASTCALL,
     "take_cdr(port, subscriber_slot, copies, borrowed, decode_body) -> message, None, False (nothing, but "
     "check the publisher), (memory, size) to finish, or (memory, size, layout) accounted for, to decode"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "hetros.transport.shm._cslot", "The compiled hot path of the shared-memory transport.",
    -1, module_functions,
};

static int intern_names(void)
{
    struct { PyObject **slot; const char *text; } names[] = {
        {&str_publisher, "_publisher"}, {&str_credits_at, "credits_at"}, {&str_blocking, "blocking"},
        {&str_room, "room"}, {&str_next_seq, "next_seq"}, {&str_wakes_version, "_wakes_version"},
        {&str_wakes, "_wakes"}, {&str_payload_ptr, "payload_ptr"}, {&str_send, "send"}, {&str_receive, "receive"},
        {&str_header, "header"}, {&str_number_of_elements, "number_of_elements"}, {&str_subscriber, "subscriber"},
        {&str_service, "service"}, {&str_expected, "expected"}, {&str_suspect_since, "suspect_since"},
        {&str_depth, "depth"}, {&str_qos, "qos"},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if ((*names[i].slot = PyUnicode_InternFromString(names[i].text)) == NULL)
            return -1;
    return 0;
}

PyMODINIT_FUNC PyInit__cslot(void)
{
    if (PyType_Ready(&MemoryType) < 0 || intern_names() < 0)
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

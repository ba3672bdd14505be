/* A generated rhs(t, y, p) / jac(t, y, p) called from Python at C speed (symmech/numerics/fastcall.py builds
 * and loads this file).
 *
 * Kernel(n, m, ndim, general) is a callable for the lengths n of y and m of p and the rank of its output:
 * (n,) for rhs (ndim 1), (n, n) for jac (ndim 2). Until bind(address, owner, general) gives it a C kernel
 *     int kernel(double t, const double *y, const double *p, double *out)
 * (0: out written; else the kernel raised, e.g. a singular mass matrix), every call goes to ``general``.
 * Once bound, a call (vectorcall) with a Python float or int t and float64 C-contiguous 1-d numpy arrays
 * y (n,) and p (m,) allocates the output, runs the kernel and returns the output; anything else (lists,
 * another dtype or length, an (n, k) batch, keywords), or a kernel that fails, goes to ``general``, the
 * module's Python path, which decides (converts, or raises its own error), so the semantics stay those of
 * ``general``. ``owner`` keeps the kernel's machine code alive (numba's cfunc). Instances have a __dict__
 * for __doc__, __name__, __wrapped__...
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <stddef.h>
#include <stdint.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#ifndef Py_TPFLAGS_HAVE_VECTORCALL /* public from Python 3.12 */
#define Py_TPFLAGS_HAVE_VECTORCALL _Py_TPFLAGS_HAVE_VECTORCALL
#endif

typedef int (*kernel_fn)(double t, const double *y, const double *p, double *out);

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    kernel_fn kernel; /* NULL until bind */
    npy_intp n, m;
    int ndim;
    PyObject *general;
    PyObject *owner;
    PyObject *dict; /* __doc__, __name__, ...: set by the caller (functools.update_wrapper) */
} Kernel;

/* t as a double when it is a Python float (numpy.float64 included) or int; 0 otherwise (no error set). */
static int as_time(PyObject *o, double *t)
{
    if (PyFloat_Check(o)) {
        *t = PyFloat_AS_DOUBLE(o);
        return 1;
    }
    if (PyLong_Check(o)) {
        *t = PyLong_AsDouble(o);
        if (*t == -1.0 && PyErr_Occurred()) { /* too large: general's float(t) raises it */
            PyErr_Clear();
            return 0;
        }
        return 1;
    }
    return 0;
}

/* The data of a native float64 C-contiguous aligned 1-d array of length n; NULL otherwise. */
static const double *as_vector(PyObject *o, npy_intp n)
{
    if (!PyArray_Check(o))
        return NULL;
    PyArrayObject *a = (PyArrayObject *)o;
    if (PyArray_TYPE(a) != NPY_DOUBLE || PyArray_NDIM(a) != 1 || PyArray_DIM(a, 0) != n ||
        !PyArray_IS_C_CONTIGUOUS(a) || !PyArray_ISALIGNED(a) || !PyArray_ISNOTSWAPPED(a))
        return NULL;
    return (const double *)PyArray_DATA(a);
}

static PyObject *Kernel_vectorcall(PyObject *callable, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Kernel *self = (Kernel *)callable;
    double t;
    const double *y, *p;
    if (self->kernel != NULL && PyVectorcall_NARGS(nargsf) == 3 && kwnames == NULL && as_time(args[0], &t) &&
        (y = as_vector(args[1], self->n)) != NULL && (p = as_vector(args[2], self->m)) != NULL) {
        npy_intp shape[2] = {self->n, self->n};
        PyObject *out = PyArray_SimpleNew(self->ndim, shape, NPY_DOUBLE);
        if (out == NULL)
            return NULL;
        if (self->kernel(t, y, p, (double *)PyArray_DATA((PyArrayObject *)out)) == 0)
            return out;
        Py_DECREF(out); /* the kernel raised: general raises the same error with its message */
    }
    return PyObject_Vectorcall(self->general, args, nargsf, kwnames);
}

static PyObject *Kernel_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    static char *names[] = {"n", "m", "ndim", "general", NULL};
    Py_ssize_t n, m;
    int ndim;
    PyObject *general;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "nniO", names, &n, &m, &ndim, &general))
        return NULL;
    if (n < 1 || m < 0 || (ndim != 1 && ndim != 2) || !PyCallable_Check(general)) {
        PyErr_SetString(PyExc_ValueError, "Kernel: n >= 1, m >= 0, ndim 1 or 2, general callable");
        return NULL;
    }
    Kernel *self = (Kernel *)type->tp_alloc(type, 0);
    if (self == NULL)
        return NULL;
    self->vectorcall = Kernel_vectorcall;
    self->n = n;
    self->m = m;
    self->ndim = ndim;
    Py_INCREF(general);
    self->general = general;
    Py_INCREF(Py_None);
    self->owner = Py_None;
    return (PyObject *)self;
}

static PyObject *Kernel_bind(Kernel *self, PyObject *args)
{
    unsigned long long address;
    PyObject *owner, *general;
    if (!PyArg_ParseTuple(args, "KOO:bind", &address, &owner, &general))
        return NULL;
    if (address == 0 || !PyCallable_Check(general)) {
        PyErr_SetString(PyExc_ValueError, "bind: address must be non-zero, general callable");
        return NULL;
    }
    Py_INCREF(owner);
    Py_INCREF(general);
    Py_SETREF(self->owner, owner);
    Py_SETREF(self->general, general);
    self->kernel = (kernel_fn)(uintptr_t)address;
    Py_RETURN_NONE;
}

static int Kernel_traverse(Kernel *self, visitproc visit, void *arg)
{
    Py_VISIT(self->general);
    Py_VISIT(self->owner);
    Py_VISIT(self->dict);
    return 0;
}

static int Kernel_clear(Kernel *self)
{
    Py_CLEAR(self->general);
    Py_CLEAR(self->owner);
    Py_CLEAR(self->dict);
    return 0;
}

static void Kernel_dealloc(Kernel *self)
{
    PyObject_GC_UnTrack(self);
    Kernel_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* pickled by name, as a module-level function is: the module's attribute in the loading process */
static PyObject *Kernel_reduce(Kernel *self, PyObject *unused)
{
    return PyObject_GetAttrString((PyObject *)self, "__qualname__");
}

static PyMemberDef Kernel_members[] = {
    {"general", T_OBJECT_EX, offsetof(Kernel, general), READONLY, "the Python path"},
    {"owner", T_OBJECT_EX, offsetof(Kernel, owner), READONLY, "what keeps the kernel's code alive"},
    {NULL},
};

static PyObject *Kernel_bound(Kernel *self, void *unused)
{
    return PyBool_FromLong(self->kernel != NULL);
}

static PyGetSetDef Kernel_getset[] = {
    {"bound", (getter)Kernel_bound, NULL, "whether bind gave it a kernel", NULL},
    {"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict, NULL, NULL},
    {NULL},
};

static PyMethodDef Kernel_methods[] = {
    {"__reduce__", (PyCFunction)Kernel_reduce, METH_NOARGS, NULL},
    {"bind", (PyCFunction)Kernel_bind, METH_VARARGS, "bind(address, owner, general): call the C kernel at address"},
    {NULL},
};

static PyTypeObject KernelType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "symmech.numerics._fastcall.Kernel",
    .tp_basicsize = sizeof(Kernel),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_new = Kernel_new,
    .tp_dealloc = (destructor)Kernel_dealloc,
    .tp_traverse = (traverseproc)Kernel_traverse,
    .tp_clear = (inquiry)Kernel_clear,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(Kernel, vectorcall),
    .tp_dictoffset = offsetof(Kernel, dict),
    .tp_members = Kernel_members,
    .tp_getset = Kernel_getset,
    .tp_methods = Kernel_methods,
};

static struct PyModuleDef fastcall_module = {
    PyModuleDef_HEAD_INIT,
    .m_name = "_fastcall",
    .m_doc = "C-speed calls of generated right-hand sides (symmech.numerics.fastcall).",
    .m_size = -1,
};

PyMODINIT_FUNC PyInit__fastcall(void)
{
    import_array();
    if (PyType_Ready(&KernelType) < 0)
        return NULL;
    PyObject *module = PyModule_Create(&fastcall_module);
    if (module == NULL)
        return NULL;
    Py_INCREF(&KernelType);
    if (PyModule_AddObject(module, "Kernel", (PyObject *)&KernelType) < 0) {
        Py_DECREF(&KernelType);
        Py_DECREF(module);
        return NULL;
    }
    return module;
}

/* The table of CPython C-API functions the shim calls, resolved with dlsym (no link-time
 * libpython; see railcontact_fmu.h). */
#define _GNU_SOURCE
#include <dlfcn.h>

#include "railcontact_fmu.h"

PythonApi py;

void *sym(void *lib, const char *name) { return dlsym(lib ? lib : RTLD_DEFAULT, name); }

int resolve(void *lib, Str *err) {
#define R(field, name)                                                                 \
    py.field = sym(lib, name);                                                         \
    if (!py.field) {                                                                   \
        str_add(err, "the CPython function %s is not in the Python library", name);  \
        return 0;                                                                      \
    }
    R(IsInitialized, "Py_IsInitialized");
    R(InitializeEx, "Py_InitializeEx");
    R(DecodeLocale, "Py_DecodeLocale");
    R(EvalSaveThread, "PyEval_SaveThread");
    R(GILEnsure, "PyGILState_Ensure");
    R(GILRelease, "PyGILState_Release");
    R(GILThisThread, "PyGILState_GetThisThreadState");
    R(DictNew, "PyDict_New");
    R(DictSetItemString, "PyDict_SetItemString");
    R(DictGetItemString, "PyDict_GetItemString");
    R(UnicodeFromString, "PyUnicode_FromString");
    R(UnicodeAsUTF8, "PyUnicode_AsUTF8");
    R(RunStringFlags, "PyRun_StringFlags");
    R(GetAttrString, "PyObject_GetAttrString");
    R(CallObject, "PyObject_CallObject");
    R(BuildValue, "Py_BuildValue");
    R(LongAsLong, "PyLong_AsLong");
    R(LongAsULL, "PyLong_AsUnsignedLongLong");
    R(TupleGetItem, "PyTuple_GetItem");
    R(BytesSize, "PyBytes_Size");
    R(BytesAsString, "PyBytes_AsString");
    R(BytesFromStringAndSize, "PyBytes_FromStringAndSize");
    R(DecRef, "Py_DecRef");
    R(ErrOccurred, "PyErr_Occurred");
    R(ErrClear, "PyErr_Clear");
#undef R
    py.SetPythonHome = sym(lib, "Py_SetPythonHome"); /* optional (removed in 3.13) */
    return 1;
}

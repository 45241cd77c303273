#include "yaml_tree.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

static sd_ynode *node_new(sd_ynode_kind k, const yaml_mark_t *m)
{
    sd_ynode *n = calloc(1, sizeof(*n));
    if (!n) return NULL;
    n->kind = k;
    n->line = (int)m->line + 1;
    n->col = (int)m->column + 1;
    return n;
}

void sd_yaml_free(sd_ynode *n)
{
    if (!n) return;
    free(n->value);
    for (int i = 0; i < n->n; i++) {
        sd_yaml_free(n->items[i]);
        if (n->keys) free(n->keys[i]);
    }
    free(n->items);
    free(n->keys);
    free(n->key_line);
    free(n->key_col);
    free(n);
}

static int push_child(sd_ynode *p, sd_ynode *c, char *key, int kl, int kc)
{
    if (p->n == p->cap) { /* (room doubled: a map of many keys grows in linear time) */
        const int cap = p->cap ? 2 * p->cap : 8;
        sd_ynode **it = realloc(p->items, (size_t)cap * sizeof(*it));
        if (!it) return -1;
        p->items = it;
        if (p->kind == SD_Y_MAP) {
            char **k = realloc(p->keys, (size_t)cap * sizeof(*k));
            if (!k) return -1;
            p->keys = k;
            int *l = realloc(p->key_line, (size_t)cap * sizeof(int));
            if (!l) return -1;
            p->key_line = l;
            int *c2 = realloc(p->key_col, (size_t)cap * sizeof(int));
            if (!c2) return -1;
            p->key_col = c2;
        }
        p->cap = cap;
    }
    if (p->kind == SD_Y_MAP) {
        p->keys[p->n] = key;
        p->key_line[p->n] = kl;
        p->key_col[p->n] = kc;
    }
    p->items[p->n++] = c;
    return 0;
}

/* The parser and the count of nodes made so far; the functions below get a pointer to its
 * first member, the parser, and reach the count through it. */
typedef struct {
    yaml_parser_t ps;
    long nodes;
} reader;

/* Recursive descent over parser events, at most SD_YAML_MAX_DEPTH collections deep. */
static sd_ynode *parse_node(yaml_parser_t *ps, yaml_event_t *ev, const char *name, char *err, int errlen, int depth);

typedef struct {
    const char *key;
    int i;
} key_at;

static int cmp_key(const void *a, const void *b)
{
    const key_at *x = a, *y = b;
    const int c = strcmp(x->key, y->key);
    return c ? c : (x->i > y->i) - (x->i < y->i);
}

/* A key that a map holds twice: its second place (reported), or -1. Sorted, in O(n log n):
 * a map of 30,000 keys took ~19 s when each key was compared with those before it. */
static int duplicate_key(const sd_ynode *n)
{
    if (n->n < 2) return -1;
    key_at *ix = malloc((size_t)n->n * sizeof *ix);
    if (!ix) return -1;
    for (int i = 0; i < n->n; i++)
        ix[i] = (key_at){n->keys[i], i};
    qsort(ix, (size_t)n->n, sizeof *ix, cmp_key);
    int dup = -1;
    for (int k = 1; k < n->n; k++)
        if (!strcmp(ix[k - 1].key, ix[k].key) && (dup < 0 || ix[k].i < dup)) dup = ix[k].i;
    free(ix);
    return dup;
}

static sd_ynode *parse_collection(yaml_parser_t *ps, sd_ynode *n, const char *name, char *err, int errlen, int depth)
{
    for (;;) {
        yaml_event_t ev;
        if (!yaml_parser_parse(ps, &ev)) {
            snprintf(err, (size_t)errlen, "%s:%d:%d: %s", name, (int)ps->problem_mark.line + 1,
                     (int)ps->problem_mark.column + 1, ps->problem ? ps->problem : "YAML error");
            sd_yaml_free(n);
            return NULL;
        }
        if (ev.type == YAML_SEQUENCE_END_EVENT || ev.type == YAML_MAPPING_END_EVENT) {
            yaml_event_delete(&ev);
            const int d = n->kind == SD_Y_MAP ? duplicate_key(n) : -1;
            if (d >= 0) {
                snprintf(err, (size_t)errlen, "%s:%d:%d: duplicate key '%s'", name, n->key_line[d], n->key_col[d],
                         n->keys[d]);
                sd_yaml_free(n);
                return NULL;
            }
            return n;
        }
        char *key = NULL;
        int kl = 0, kc = 0;
        if (n->kind == SD_Y_MAP) {
            if (ev.type != YAML_SCALAR_EVENT) {
                snprintf(err, (size_t)errlen, "%s:%d:%d: mapping keys must be plain words", name,
                         (int)ev.start_mark.line + 1, (int)ev.start_mark.column + 1);
                yaml_event_delete(&ev);
                sd_yaml_free(n);
                return NULL;
            }
            key = strdup((const char *)ev.data.scalar.value);
            kl = (int)ev.start_mark.line + 1;
            kc = (int)ev.start_mark.column + 1;
            yaml_event_delete(&ev);
            if (!yaml_parser_parse(ps, &ev)) {
                snprintf(err, (size_t)errlen, "%s:%d:%d: %s", name, (int)ps->problem_mark.line + 1,
                         (int)ps->problem_mark.column + 1, ps->problem ? ps->problem : "YAML error");
                free(key);
                sd_yaml_free(n);
                return NULL;
            }
        }
        sd_ynode *c = parse_node(ps, &ev, name, err, errlen, depth);
        if (!c || push_child(n, c, key, kl, kc)) {
            free(key);
            sd_yaml_free(c);
            sd_yaml_free(n);
            return NULL;
        }
    }
}

static sd_ynode *parse_node(yaml_parser_t *ps, yaml_event_t *ev, const char *name, char *err, int errlen, int depth)
{
    sd_ynode *n = NULL;
    if (++((reader *)ps)->nodes > SD_YAML_MAX_NODES) {
        snprintf(err, (size_t)errlen, "%s:%d:%d: more than %d values in one document", name, (int)ev->start_mark.line + 1,
                 (int)ev->start_mark.column + 1, SD_YAML_MAX_NODES);
        yaml_event_delete(ev);
        return NULL;
    }
    if ((ev->type == YAML_SEQUENCE_START_EVENT || ev->type == YAML_MAPPING_START_EVENT) && depth >= SD_YAML_MAX_DEPTH) {
        snprintf(err, (size_t)errlen, "%s:%d:%d: nested deeper than %d levels", name, (int)ev->start_mark.line + 1,
                 (int)ev->start_mark.column + 1, SD_YAML_MAX_DEPTH);
        yaml_event_delete(ev);
        return NULL;
    }
    switch (ev->type) {
    case YAML_SCALAR_EVENT:
        n = node_new(SD_Y_SCALAR, &ev->start_mark);
        if (n) n->value = strdup((const char *)ev->data.scalar.value);
        yaml_event_delete(ev);
        return n;
    case YAML_SEQUENCE_START_EVENT:
        n = node_new(SD_Y_SEQ, &ev->start_mark);
        yaml_event_delete(ev);
        return n ? parse_collection(ps, n, name, err, errlen, depth + 1) : NULL;
    case YAML_MAPPING_START_EVENT:
        n = node_new(SD_Y_MAP, &ev->start_mark);
        yaml_event_delete(ev);
        return n ? parse_collection(ps, n, name, err, errlen, depth + 1) : NULL;
    case YAML_ALIAS_EVENT:
        snprintf(err, (size_t)errlen, "%s:%d:%d: YAML aliases are not supported", name, (int)ev->start_mark.line + 1,
                 (int)ev->start_mark.column + 1);
        yaml_event_delete(ev);
        return NULL;
    default:
        snprintf(err, (size_t)errlen, "%s:%d:%d: unexpected YAML event", name, (int)ev->start_mark.line + 1,
                 (int)ev->start_mark.column + 1);
        yaml_event_delete(ev);
        return NULL;
    }
}

static sd_ynode *parse_all(yaml_parser_t *ps, const char *name, char *err, int errlen)
{
    sd_ynode *root = NULL;
    for (;;) {
        yaml_event_t ev;
        if (!yaml_parser_parse(ps, &ev)) {
            snprintf(err, (size_t)errlen, "%s:%d:%d: %s", name, (int)ps->problem_mark.line + 1,
                     (int)ps->problem_mark.column + 1, ps->problem ? ps->problem : "YAML error");
            sd_yaml_free(root);
            return NULL;
        }
        yaml_event_type_t t = ev.type;
        if (t == YAML_STREAM_END_EVENT) {
            yaml_event_delete(&ev);
            break;
        }
        if (t == YAML_SEQUENCE_START_EVENT || t == YAML_MAPPING_START_EVENT || t == YAML_SCALAR_EVENT ||
            t == YAML_ALIAS_EVENT) {
            if (root) {
                snprintf(err, (size_t)errlen, "%s:%d:%d: only one YAML document is allowed", name,
                         (int)ev.start_mark.line + 1, (int)ev.start_mark.column + 1);
                yaml_event_delete(&ev);
                sd_yaml_free(root);
                return NULL;
            }
            root = parse_node(ps, &ev, name, err, errlen, 0);
            if (!root) return NULL;
            continue;
        }
        yaml_event_delete(&ev);
    }
    if (!root) snprintf(err, (size_t)errlen, "%s:1:1: empty scenario", name);
    return root;
}

static sd_ynode *parse_bytes(const unsigned char *text, size_t len, const char *name, char *err, int errlen)
{
    reader r = {.nodes = 0};
    if (!yaml_parser_initialize(&r.ps)) {
        snprintf(err, (size_t)errlen, "%s: out of memory", name);
        return NULL;
    }
    yaml_parser_set_input_string(&r.ps, text, len);
    sd_ynode *root = parse_all(&r.ps, name, err, errlen);
    yaml_parser_delete(&r.ps);
    return root;
}

sd_ynode *sd_yaml_load(const char *path, char *err, int errlen)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, (size_t)errlen, "%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    /* read whole, up to the limit and one byte more (a pipe or a device too, never past it) */
    size_t n = 0, cap = 0, got = 1;
    unsigned char *buf = NULL;
    while (got > 0 && n <= SD_YAML_MAX_BYTES) {
        if (n == cap) {
            cap = cap ? 2 * cap : 16384;
            if (cap > SD_YAML_MAX_BYTES + 1) cap = SD_YAML_MAX_BYTES + 1;
            unsigned char *nb = realloc(buf, cap);
            if (!nb) {
                free(buf);
                fclose(f);
                snprintf(err, (size_t)errlen, "%s: out of memory", path);
                return NULL;
            }
            buf = nb;
        }
        got = fread(buf + n, 1, cap - n, f);
        n += got;
    }
    const int rerr = ferror(f);
    const int e = errno;
    fclose(f);
    sd_ynode *root = NULL;
    if (rerr)
        snprintf(err, (size_t)errlen, "%s: read error: %s", path, strerror(e));
    else if (n > SD_YAML_MAX_BYTES)
        snprintf(err, (size_t)errlen, "%s: longer than %d MiB (a scenario or sweep file is a few KB)", path,
                 SD_YAML_MAX_BYTES / (1024 * 1024));
    else
        root = parse_bytes(buf, n, path, err, errlen);
    free(buf);
    return root;
}

sd_ynode *sd_yaml_parse_string(const char *text, const char *name, char *err, int errlen)
{
    return parse_bytes((const unsigned char *)text, strlen(text), name, err, errlen);
}

const sd_ynode *sd_yaml_get(const sd_ynode *map, const char *key)
{
    if (!map || map->kind != SD_Y_MAP) return NULL;
    for (int i = 0; i < map->n; i++)
        if (strcmp(map->keys[i], key) == 0) return map->items[i];
    return NULL;
}

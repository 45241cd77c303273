/* A YAML document read with libyaml into a small tree that remembers line and column, so that
 * every error can name file:line:col. */
#ifndef SD_YAML_TREE_H
#define SD_YAML_TREE_H

typedef enum { SD_Y_SCALAR, SD_Y_MAP, SD_Y_SEQ } sd_ynode_kind;

typedef struct sd_ynode {
    sd_ynode_kind kind;
    int line, col; /* 1-based */
    char *value;   /* scalar text */
    int n, cap;    /* children (seq items, or map values), and the room for them */
    char **keys;   /* map keys */
    int *key_line, *key_col;
    struct sd_ynode **items;
} sd_ynode;

/* Collections nest at most this deep: deeper input is refused (the reader recurses). */
#define SD_YAML_MAX_DEPTH 64

/* A file is read up to this many bytes (a scenario is a few KB); a longer one is refused, and so
 * is a document of more nodes (scalars and collections) than SD_YAML_MAX_NODES. */
#define SD_YAML_MAX_BYTES (4 * 1024 * 1024)
#define SD_YAML_MAX_NODES 500000

/* Parse a file; returns NULL and writes "file:line:col: message" into err on failure. */
sd_ynode *sd_yaml_load(const char *path, char *err, int errlen);
sd_ynode *sd_yaml_parse_string(const char *text, const char *name, char *err, int errlen);
void sd_yaml_free(sd_ynode *n);
const sd_ynode *sd_yaml_get(const sd_ynode *map, const char *key);

#endif

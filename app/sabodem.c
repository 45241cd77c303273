#include <stdio.h>
#include "sabodem.h"
int main(void) { printf("%s\n", sd_status_message(SD_OK)); return 0; }

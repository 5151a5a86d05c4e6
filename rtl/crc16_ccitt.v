// crc16_ccitt: one byte of CRC-16/CCITT-FALSE (poly 0x1021, MSB first, no reflection), combinational.
//
// The frame CRC starts at OMNILOC_CRC_INIT (0xFFFF) and runs over LEN, TYPE and body; the check
// value of the ASCII string "123456789" is 0x29B1 (tests/rtl/tb_crc16_ccitt.cpp).
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module crc16_ccitt (
    input  wire [15:0] crc_i,
    input  wire [7:0]  data_i,
    output reg  [15:0] crc_o
);
integer i;
always @(*) begin
    crc_o = crc_i ^ {data_i, 8'h00};
    for (i = 0; i < 8; i = i + 1) begin
        crc_o = crc_o[15] ? ((crc_o << 1) ^ `OMNILOC_CRC_POLY) : (crc_o << 1);
    end
end

// Only when this module is the proof's top (tests/formal/run_formal.sh defines FORMAL_TOP_<TOP>):
// proven once for all inputs, it is a fact the modules that instantiate it may rely on, and carried
// into their proofs (frame_tx, frame_rx) it made z3 stall for more than 15 minutes on frame_tx.
`ifdef FORMAL_TOP_CRC16_CCITT
// Independent reference: the byte-at-a-time form of the same CRC (no bit loop; valid for the
// polynomial 0x1021 only, hence the first assertion): x = high byte ^ data, x ^= x >> 4,
// crc = (crc << 8) ^ (x << 12) ^ (x << 5) ^ x. Proven for all 2^24 inputs at once.
reg [7:0]  f_x;
reg [15:0] f_crc;
always @(*) begin
    f_x = crc_i[15:8] ^ data_i;
    f_x = f_x ^ (f_x >> 4);
    f_crc = {crc_i[7:0], 8'h00} ^ ({8'h00, f_x} << 12) ^ ({8'h00, f_x} << 5) ^ {8'h00, f_x};
    assert (`OMNILOC_CRC_POLY == 16'h1021);
    assert (crc_o == f_crc);
    // The check value's first step (tests/rtl/tb_crc16_ccitt.cpp runs the whole string): 0xFFFF, '1'.
    if (crc_i == 16'hFFFF && data_i == 8'h31) assert (crc_o == 16'hC782);
    // A zero byte maps a non-zero state to a non-zero one: it multiplies the state by x^8 modulo
    // the polynomial, and x is invertible modulo a polynomial with a constant term (0x1021 has one).
    if (crc_i != 16'h0000 && data_i == 8'h00) assert (crc_o != 16'h0000);
    cover (crc_o == 16'h0000 && crc_i != 16'h0000);  // a byte that completes a zero remainder
    cover (crc_i == 16'hFFFF && data_i == 8'h31);
end
`endif
endmodule

`default_nettype wire
